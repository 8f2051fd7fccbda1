#!/usr/bin/env python3
"""bench_unsync.py REL OUT RUNS - `make bench` section "unsync" (issue 15): rigpose-sim on the
smooth motion (30 fps, seed 1, RUNS runs) with free-running cameras, against the synchronised
rig on the same runs. Clocks: the issue's offsets 0, +12, -25, +40 ms on cam1..cam4 with each
stereo partner on its camera's clock (cam1b 0, cam3b -25 ms), 1 ms jitter; and the rates 30,
25, 15 Hz (cam1 and cam1b 30, cam2 and cam4 25, cam3 and cam3b 15). Ratios of the mean tx error
to the synchronised one for stereo4 and gc: uncompensated (the estimators told nothing),
offsets given (--known-offsets), offsets estimated from zero (--estimate-offsets), rates; and
the time per frame set of each case over the synchronised one's (rigpose-sim's us_per_frame,
the same machine in the same run: the cost of the per-camera-time update); the estimated
offsets' error after 50 frames (rigpose-sim's offset_err_ms_f50: mean |estimated - true| over
the filter's offset states, relative to cam1); and the instructions of one frame set through
each estimator (callgrind on rigpose-sim's stereo_step / gc_step, 2 runs x 60 frames, seed 1)
synchronised, with the offsets given (the per-camera-time update) and estimated.
Writes OUT (one flat JSON object) and prints the table; the figures and their reading are in
docs/time.md."""
import json
import os
import subprocess
import sys
import tempfile

rel, out, runs = sys.argv[1], sys.argv[2], int(sys.argv[3])
base = [f"{rel}/rigpose-sim", "--motion", "smooth", "--methods", "stereo4,gc", "--runs",
        str(runs), "--seed", "1", "--json"]
offsets = ["--cam-offsets-ms", "0,12,-25,40,0,-25", "--jitter-ms", "1"]
cases = {
    "sync": [],
    "unsync": offsets,
    "known": offsets + ["--known-offsets"],
    "estimated": offsets + ["--estimate-offsets"],
    "rates": ["--cam-fps", "30,25,15,25,30,15"],
}
res = {}
for name, extra in cases.items():
    p = subprocess.run(base + extra, capture_output=True, text=True, check=True)
    res[name] = {r["method"]: r for r in json.loads(p.stdout)["rows"]}

fig = {"unsync_runs": runs}
print(f"{'case':<10} {'stereo4 tx m':>13} {'ratio':>7} {'time':>6} {'gc tx m':>11} {'ratio':>7}"
      f" {'time':>6}  lost (s4, gc)")
for name in cases:
    row = []
    for m in ("stereo4", "gc"):
        tx = res[name][m]["tx"]
        ratio = tx / res["sync"][m]["tx"]
        tratio = res[name][m]["us_per_frame"] / res["sync"][m]["us_per_frame"]
        fig[f"unsync_{name}_{m}_tx_m"] = tx
        if name != "sync":
            fig[f"unsync_{name}_{m}_vs_sync_tx_ratio"] = ratio
            fig[f"unsync_{name}_{m}_vs_sync_time_ratio"] = tratio
        row.append((tx, ratio, tratio, res[name][m]["lost_frames"]))
    print(f"{name:<10} {row[0][0]:13.6f} {row[0][1]:7.2f} {row[0][2]:6.2f} {row[1][0]:11.6f}"
          f" {row[1][1]:7.2f} {row[1][2]:6.2f}  {row[0][3]}, {row[1][3]}")
for m in ("stereo4", "gc"):
    fig[f"time_offset_err_ms_{m}"] = res["estimated"][m]["offset_err_ms_f50"]
    fig[f"time_offset_err_ms_{m}_max"] = res["estimated"][m]["offset_err_ms_f50_max"]
fig["time_offset_err_ms"] = max(fig["time_offset_err_ms_stereo4"], fig["time_offset_err_ms_gc"])
print(f"offsets estimated from 0, after 50 frames: mean |error| stereo4 "
      f"{fig['time_offset_err_ms_stereo4']:.3f} ms (largest {fig['time_offset_err_ms_stereo4_max']:.3f}),"
      f" gc {fig['time_offset_err_ms_gc']:.3f} ms (largest {fig['time_offset_err_ms_gc_max']:.3f});"
      f" target 0.5 ms")


def instructions_per_set(method, extra):
    """Instructions of one frame set through the method's estimator step (callgrind)."""
    runs, frames = 2, 60
    step = {"stereo4": "stereo_step", "gc": "gc_step"}[method]
    with tempfile.TemporaryDirectory() as d:
        cg = os.path.join(d, "cg.out")
        subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=" + cg,
                        "--toggle-collect=" + step, f"{rel}/rigpose-sim", "--motion", "smooth",
                        "--methods", method, "--runs", str(runs), "--frames", str(frames),
                        "--seed", "1", "--threads", "1"] + extra,
                       capture_output=True, text=True, check=True)
        with open(cg) as f:
            total = next(int(line.split()[1]) for line in f
                         if line.startswith(("summary:", "totals:")))
    return total / (runs * frames)


print(f"{'instructions per frame set':<28} {'sync':>11} {'offsets given':>14} {'ratio':>6}"
      f" {'estimated':>11} {'ratio':>6}")
for m in ("stereo4", "gc"):
    ir = {name: instructions_per_set(m, cases[name]) for name in ("sync", "known", "estimated")}
    for name in ("sync", "known", "estimated"):
        fig[f"unsync_{name}_{m}_instructions_per_set"] = round(ir[name])
    fig[f"unsync_known_{m}_vs_sync_instructions_ratio"] = ir["known"] / ir["sync"]
    fig[f"unsync_estimated_{m}_vs_sync_instructions_ratio"] = ir["estimated"] / ir["sync"]
    print(f"{m:<28} {ir['sync']:11.0f} {ir['known']:14.0f} {ir['known'] / ir['sync']:6.2f}"
          f" {ir['estimated']:11.0f} {ir['estimated'] / ir['sync']:6.2f}")
# the names: the estimator's own compensation (offsets estimated)
fig["unsync_stereo4_vs_sync_tx_ratio"] = fig["unsync_estimated_stereo4_vs_sync_tx_ratio"]
fig["unsync_gc_vs_sync_tx_ratio"] = fig["unsync_estimated_gc_vs_sync_tx_ratio"]
with open(out, "w") as f:
    json.dump(fig, f, indent=1, sort_keys=True)
