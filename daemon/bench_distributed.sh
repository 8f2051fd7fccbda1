#!/usr/bin/env bash
# bench_distributed.sh BUILD OUT.json - `make bench` section `distributed`: latency from a frame's
# capture to its pose on LCM, through four rigpose-frontend processes and the daemon with
# source.kind lcm (udpm ttl=0, this host), against the in-process daemon on the same frames in
# the same run. The frames: a rendered replay (rigpose-render, BENCH_DIST_SIZE, default 320x240:
# four 640x480 cameras at 30 Hz take more than this 2-core host's share in one process, and in
# four; BENCH_DIST_FRAMES sets at 30 Hz, default 150), method gc on the four single cameras, restamped a few seconds ahead on
# CLOCK_MONOTONIC and read with source.realtime: live (daemon/tests/restamp.py), so a frame's
# time is the moment it "is captured" (its image already decoded) for both runs; the daemon's
# --stats-json gives the percentiles over every set (1 % bins). The in-process run goes first,
# then the distributed one, never both at once.
set -u
BUILD=${1:?usage: bench_distributed.sh BUILD OUT.json}
OUT=${2:?usage: bench_distributed.sh BUILD OUT.json}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
cd "$ROOT"
REL=$BUILD/release
PY=${PY:-.venv/bin/python}
N=${BENCH_DIST_FRAMES:-150}
SIZE=${BENCH_DIST_SIZE:-320x240}
URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'
TAG=B$$_$RANDOM
TMP=$(mktemp -d)
PIDS=()
trap 'for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null; done; rm -rf "$TMP"' EXIT

"$REL/rigpose-render" --out "$TMP/src" --frames "$N" --width "${SIZE%x*}" --height "${SIZE#*x}" \
    --ss 1 > "$TMP/render.out" 2>&1 \
  || { cat "$TMP/render.out"; echo "bench_distributed: render failed" >&2; exit 1; }

# In-process: the daemon reads the replay itself (images -> trackers -> estimator).
"$PY" daemon/tests/restamp.py "$TMP/src" "$TMP" in 1.5 "$TAG"
"$REL/rigpose" --config "$TMP/in_replay.yaml" --lcm-url "$URL" --quiet \
    --stats-json "$TMP/in.json" > "$TMP/in.out" 2>&1 \
  || { cat "$TMP/in.out"; echo "bench_distributed: in-process daemon failed" >&2; exit 1; }

# Distributed: four front ends (one camera each), the daemon on their features.
"$PY" daemon/tests/restamp.py "$TMP/src" "$TMP" dist 2.5 "$TAG"
"$REL/rigpose" --config "$TMP/dist_lcm.yaml" --lcm-url "$URL" --quiet --frames "$N" \
    --stats-json "$TMP/dist.json" > "$TMP/dist.out" 2>&1 &
DPID=$!; PIDS+=("$DPID")
for k in 0 1 2 3; do
  "$REL/rigpose-frontend" --config "$TMP/dist_replay.yaml" --cameras $k --lcm-url "$URL" \
      --quiet > "$TMP/fe$k.out" 2>&1 &
  PIDS+=("$!")
done
( sleep $((N / 30 + 30)); kill -TERM $DPID 2>/dev/null ) & PIDS+=("$!")
wait $DPID || { cat "$TMP/dist.out"; echo "bench_distributed: daemon failed" >&2; exit 1; }

"$PY" - "$TMP/in.json" "$TMP/dist.json" "$OUT" "$N" "$SIZE" <<'PYEOF'
import json, os, sys
a, b = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
d = {"distributed_latency_ms_p50": b["daemon_latency_ms_p50"],
     "distributed_latency_ms_p99": b["daemon_latency_ms_p99"],
     "distributed_inprocess_latency_ms_p50": a["daemon_latency_ms_p50"],
     "distributed_inprocess_latency_ms_p99": a["daemon_latency_ms_p99"],
     "distributed_vs_inprocess_latency_p99_ratio":
         b["daemon_latency_ms_p99"] / a["daemon_latency_ms_p99"]}
json.dump(d, open(sys.argv[3], "w"))
print("distributed: %s sets at 30 Hz, %s, gc on 4 cameras; frame -> pose on LCM (udpm ttl=0); "
      "load average %.1f on %d cores" % (sys.argv[4], sys.argv[5], os.getloadavg()[0], os.cpu_count()))
print("  4 rigpose-frontend + daemon (source lcm): p50 %8.3f ms  p99 %8.3f ms  (target p99 <= 10)"
      % (d["distributed_latency_ms_p50"], d["distributed_latency_ms_p99"]))
print("  in-process daemon (source replay):        p50 %8.3f ms  p99 %8.3f ms"
      % (d["distributed_inprocess_latency_ms_p50"], d["distributed_inprocess_latency_ms_p99"]))
PYEOF
