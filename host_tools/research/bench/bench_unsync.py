#!/usr/bin/env python3
"""bench_unsync.py REL OUT RUNS - `make bench` section "unsync" (issue 15): rigpose-sim on the
smooth motion (30 fps, seed 1, RUNS runs) with free-running cameras, against the synchronised
rig on the same runs. Clocks: the issue's offsets 0, +12, -25, +40 ms on cam1..cam4 with each
stereo partner on its camera's clock (cam1b 0, cam3b -25 ms), 1 ms jitter; and the rates 30,
25, 15 Hz (cam1 and cam1b 30, cam2 and cam4 25, cam3 and cam3b 15). Ratios of the mean tx error
to the synchronised one for stereo4 and gc: uncompensated (the estimators told nothing),
offsets given (--known-offsets), offsets estimated from zero (--estimate-offsets), rates; and
the time per frame set of each case over the synchronised one's (rigpose-sim's us_per_frame,
the same machine in the same run: the cost of the per-camera-time update).
Writes OUT (one flat JSON object) and prints the table; the figures and their reading are in
docs/time.md."""
import json
import subprocess
import sys

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
# the names: the estimator's own compensation (offsets estimated)
fig["unsync_stereo4_vs_sync_tx_ratio"] = fig["unsync_estimated_stereo4_vs_sync_tx_ratio"]
fig["unsync_gc_vs_sync_tx_ratio"] = fig["unsync_estimated_gc_vs_sync_tx_ratio"]
with open(out, "w") as f:
    json.dump(fig, f, indent=1, sort_keys=True)
