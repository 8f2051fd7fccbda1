#!/usr/bin/env python3
"""threads_ab.py CONFIG ROUNDS OUT BIN_A BIN_B - two builds of the daemon on one replay, 1 and 2
threads (--fast, --quiet), alternating A and B (the order swapped every round) so that both see
the same states of a shared machine; before each run waits (up to 2 min) for 3 s in which the
machine's CPUs were busy for at most 80 ms, and records the CPU time others took during the run
(/proc/stat busy minus the run's own). Prints every run and the median and mean frame sets per
second per build and thread count; writes every run to OUT (JSON). The bench recipe's best of 2
(bench_threads.sh) is at the mercy of one fast or slow run; this compares distributions.

  build/release/rigpose-render --out /tmp/r --frames 100 --ss 1
  .venv/bin/python daemon/tests/rig_subset.py /tmp/r/rig.yaml /tmp/r/rig4.yaml cam2 cam4
  host_tools/research/bench/threads_ab.py /tmp/r/rig4.yaml 8 /tmp/ab.json OLD/rigpose build/release/rigpose
"""
import json, os, resource, statistics, subprocess, sys, tempfile, time


def stat():
    v = list(map(int, open("/proc/stat").readline().split()[1:9]))
    return sum(v), v[3] + v[4]  # all, idle + iowait (ticks)


def quiet(max_wait_s=120):
    t0 = time.time()
    while time.time() - t0 < max_wait_s:
        a = stat()
        time.sleep(3.0)
        b = stat()
        if (b[0] - a[0]) - (b[1] - a[1]) <= 8:
            return True
    return False


def main():
    if len(sys.argv) != 6:
        sys.exit(__doc__)
    config, rounds, out, bins = sys.argv[1], int(sys.argv[2]), sys.argv[3], {"A": sys.argv[4], "B": sys.argv[5]}
    tmp = tempfile.mkdtemp()
    tck = os.sysconf("SC_CLK_TCK")
    runs = []
    for r in range(rounds):
        for name in ("A", "B") if r % 2 == 0 else ("B", "A"):
            for n in (1, 2):
                q = quiet()
                a = stat()
                ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
                sj = os.path.join(tmp, "s.json")
                subprocess.run([bins[name], "--config", config, "--fast", "--quiet", "--threads", str(n),
                                "--lcm-url", "file://%s/p.log?mode=w" % tmp, "--stats-json", sj],
                               stdout=subprocess.DEVNULL, check=True)
                b = stat()
                ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
                own = (ru1.ru_utime + ru1.ru_stime) - (ru0.ru_utime + ru0.ru_stime)
                others = ((b[0] - a[0]) - (b[1] - a[1])) / tck - own
                rec = dict(round=r, build=name, threads=n, fps=json.load(open(sj))["daemon_fps"],
                           quiet_before=q, others_cpu_s=round(others, 2))
                runs.append(rec)
                print(rec, flush=True)
    json.dump(runs, open(out, "w"), indent=1)
    for name in ("A", "B"):
        for n in (1, 2):
            v = sorted(x["fps"] for x in runs if x["build"] == name and x["threads"] == n)
            print("%s (%s) threads %d: median %.1f mean %.1f sets/s over %d runs %s"
                  % (name, bins[name], n, statistics.median(v), statistics.mean(v), len(v), v))


if __name__ == "__main__":
    main()
