#!/usr/bin/env python3
"""bench_track.py - `make bench` section "track": runs the tracker benchmark (rigpose vs OpenCV),
counts the instructions of steady-state frame sets with callgrind, reads the core's static memory
with `size`, prints a table and writes one flat JSON object of figures.

usage: bench_track.py --bench BIN --driver BIN --static-pipe OBJ --static-gc OBJ --core-lib LIB
                      --out FILE [--frames N] [--reps R] [--warm W] [--measure M]
"""
import argparse
import json
import os
import re
import subprocess
import sys


def run(cmd):
    print("+ " + " ".join(cmd), flush=True)
    return subprocess.run(cmd, check=True, stdout=subprocess.PIPE, text=True).stdout


def size_ram(path):
    """data + bss of an object or archive (berkeley `size -t`: the total line)."""
    out = run(["size", "-t", path]).strip().splitlines()[-1].split()
    text, data, bss = int(out[0]), int(out[1]), int(out[2])
    return text, data + bss


def callgrind_per_frameset(driver, layout, size, warm, measure, workdir):
    """Instructions of each measured frame set (callgrind dumps after every bt_measured call):
    returns (mean, max). gc's window adjustment runs on some frame sets only (every 8 frames),
    so the mean is what a frame set costs on average and the max what the worst one costs."""
    out = os.path.join(workdir, "callgrind.%s.%d.out" % (layout, size))
    for old in [f for f in os.listdir(workdir) if f.startswith(os.path.basename(out))]:
        os.remove(os.path.join(workdir, old))
    cmd = ["valgrind", "--tool=callgrind", "--callgrind-out-file=" + out,
           "--toggle-collect=bt_measured", "--dump-after=bt_measured", driver, "--size",
           str(size), "--layout", layout, "--warm", str(warm), "--measure", str(measure)]
    print("+ " + " ".join(cmd), flush=True)
    res = subprocess.run(cmd, check=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True)
    sys.stdout.write(res.stdout)
    per = []
    for name in os.listdir(workdir):
        m = re.match(re.escape(os.path.basename(out)) + r"\.(\d+)$", name)
        if not m:
            continue
        with open(os.path.join(workdir, name)) as f:
            for line in f:
                t = re.match(r"^(totals|summary):\s+(\d+)", line)
                if t:
                    per.append(int(t.group(2)))
                    break
    per = [p for p in per if p > 0]
    if len(per) != measure:
        raise SystemExit("expected %d frame-set dumps of %s, found %d" % (measure, out, len(per)))
    return sum(per) / measure, max(per)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bench", required=True)
    ap.add_argument("--driver", required=True)
    ap.add_argument("--static-pipe", required=True)
    ap.add_argument("--static-gc", required=True)
    ap.add_argument("--core-lib", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--warm", type=int, default=5)
    ap.add_argument("--measure", type=int, default=40)
    a = ap.parse_args()
    workdir = os.path.dirname(os.path.abspath(a.out))
    fig = {}

    time_json = os.path.join(workdir, "track_time.json")
    sys.stdout.write(run([a.bench, "--frames", str(a.frames), "--reps", str(a.reps),
                          "--out", time_json]))
    with open(time_json) as f:
        fig.update(json.load(f))

    ir_gc, max_gc = callgrind_per_frameset(a.driver, "gc", 320, a.warm, a.measure, workdir)
    ir_st, max_st = callgrind_per_frameset(a.driver, "stereo4", 320, a.warm, a.measure, workdir)
    fig["frameset_instructions_320"] = round(ir_gc)
    fig["frameset_instructions_320_max"] = max_gc
    fig["frameset_instructions_320_stereo4"] = round(ir_st)
    fig["frameset_instructions_320_stereo4_max"] = max_st

    lib_text, lib_ram = size_ram(a.core_lib)
    _, pipe_ram = size_ram(a.static_pipe)
    _, gc_ram = size_ram(a.static_gc)
    fig["core_static_bytes_4cam_640"] = pipe_ram + lib_ram
    fig["core_static_bytes_4trackers_gc_640"] = gc_ram + lib_ram
    fig["core_text_bytes"] = lib_text

    print()
    print("track: figures (instructions: callgrind, each of %d frame sets after %d;"
          " memory: size, float build at 640x480)" % (a.measure, a.warm))
    rows = [
        ("tracker time ratio rigpose / OpenCV, 320x240", "tracker_vs_opencv_time_ratio_320"),
        ("tracker time ratio rigpose / OpenCV, 640x480", "tracker_vs_opencv_time_ratio_640"),
        ("instructions per frame set, gc, 320x240 (mean)", "frameset_instructions_320"),
        ("instructions of the costliest frame set, gc, 320x240", "frameset_instructions_320_max"),
        ("instructions per frame set, stereo4, 320x240 (mean)",
         "frameset_instructions_320_stereo4"),
        ("instructions of the costliest frame set, stereo4, 320x240",
         "frameset_instructions_320_stereo4_max"),
        ("static RAM, rp_pipe_t (4 trackers + estimator) + core data, bytes",
         "core_static_bytes_4cam_640"),
        ("static RAM, 4 rp_tracker_t + rp_vo_gc_t + core data, bytes",
         "core_static_bytes_4trackers_gc_640"),
        ("core code (.text), bytes", "core_text_bytes"),
    ]
    for name, key in rows:
        print("  %-68s %14s" % (name, ("%.3f" % fig[key]) if isinstance(fig[key], float)
                                 else fig[key]))
    with open(a.out, "w") as f:
        json.dump(fig, f, indent=1, sort_keys=True)
        f.write("\n")


if __name__ == "__main__":
    main()
