#!/usr/bin/env bash
# bench_threads.sh BUILD OUT [FRAMES] - `make bench` section "threads" (issue 17): frame sets per
# second of the release daemon's image pipeline on a rendered replay (rigpose-render, FRAMES
# sets, default 100, 640x480, the four cameras stereo4 uses), --fast, with --threads 1 and
# --threads 2, each run twice in alternation (the better of the two counts: the other engineers
# of a shared machine only ever slow a run down), poses to file:// logs; the speedup of 2 threads
# over 1, and whether the two runs' poses are identical (pose_log_diff.py). Writes OUT (one flat
# JSON object) and prints the table.
set -eu
BUILD=${1:?usage: bench_threads.sh BUILD OUT [FRAMES]}
OUT=${2:?usage: bench_threads.sh BUILD OUT [FRAMES]}
FRAMES=${3:-100}
. "$(dirname "$0")/../../../tests/script_env.sh"

"$REL/rigpose-render" --out "$TMP/src" --frames "$FRAMES" --ss 1 > "$TMP/render.out" 2>&1 ||
    { cat "$TMP/render.out"; exit 1; }
"$PY" daemon/tests/rig_subset.py "$TMP/src/rig.yaml" "$TMP/src/rig4.yaml" cam2 cam4
for rep in 1 2; do
  for n in 1 2; do
    "$REL/rigpose" --config "$TMP/src/rig4.yaml" --fast --quiet --threads "$n" \
        --lcm-url "file://$TMP/p$n.log?mode=w" --stats-json "$TMP/s$n.$rep.json" > /dev/null
  done
done
identical=0
"$PY" daemon/tests/pose_log_diff.py "$TMP/p1.log" "$TMP/p2.log" > "$TMP/diff.out" && identical=1
"$PY" - "$OUT" "$FRAMES" "$identical" "$TMP" <<'PYEOF'
import json, sys
out, frames, identical, tmp = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
best = {}
for n in (1, 2):
    runs = [json.load(open("%s/s%d.%d.json" % (tmp, n, rep))) for rep in (1, 2)]
    best[n] = max(runs, key=lambda r: r["daemon_fps"])
fig = {
    "threads_fps_1": round(best[1]["daemon_fps"], 2),
    "threads_fps_2": round(best[2]["daemon_fps"], 2),
    "threads2_vs_1_speedup": round(best[2]["daemon_fps"] / best[1]["daemon_fps"], 3),
    "threads_latency_ms_p99_1": round(best[1]["daemon_latency_ms_p99"], 3),
    "threads_latency_ms_p99_2": round(best[2]["daemon_latency_ms_p99"], 3),
    "threads_poses_identical": identical,
}
json.dump(fig, open(out, "w"), indent=1)
print("threads: daemon on a rendered replay, %d sets, 640x480, stereo4's 4 cameras, --fast "
      "(best of 2 runs each)" % frames)
for k, v in fig.items():
    print("  %-28s %10s" % (k, v))
print("  target: threads2_vs_1_speedup >= 1.7, threads_poses_identical = 1")
PYEOF
