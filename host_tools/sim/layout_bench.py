#!/usr/bin/env python3
"""layout_bench.py STUDY_JSON OUT_JSON - the layout study's figures for `make bench`.

Reads the output of `rigpose-sim --layout-study --json` (placements ranked by the first
method's mean translation error), prints the ranking and writes one flat JSON object: the best
placement against the paper's (mean translation error t, tx, worst run), the paper's rank and
the best placement's cam2 offset and yaw.
"""
import json
import sys


def main(argv):
    if len(argv) != 3:
        sys.stderr.write(__doc__)
        return 2
    with open(argv[1]) as f:
        study = json.load(f)
    rows = study["placements"]
    if not rows:
        sys.stderr.write("layout_bench: no placements\n")
        return 1
    method = study["ranked_by"].split()[0]
    best = rows[0]
    paper = next((r for r in rows if r["paper"]), None)
    print("\n== layout study: cam2/cam4 placements ranked by %s's mean translation error ==" % method)
    print("  %d placements (%s), %d runs x %d frames each, seed %d; t = mean of |tx|,|ty|,|tz| (m)"
          % (len(rows), study["source"], study["runs"], study["frames"], study["seed"]))
    print("  %-4s %-22s %-30s %10s %10s %10s" % ("rank", "placement", "cam2 x y z yaw(deg)",
                                              "t", "tx", "worst t"))
    for r in rows:
        if r["rank"] <= 5 or r["paper"] or r["rank"] == len(rows):
            m = r[method]
            print("  %3d%s %-22s %-30s %10.6f %10.6f %10.6f" % (
                r["rank"], "*" if r["paper"] else " ", r["name"],
                "%.4f %.4f %.4f %.0f" % tuple(r["cam2"]), m["t"], m["tx"], m["worst_run_t"]))
    fig = {"layout_placements": len(rows), "layout_runs": study["runs"]}
    b = best[method]
    fig.update({"layout_best_t_m": b["t"], "layout_best_tx_m": b["tx"],
                "layout_best_worst_run_t_m": b["worst_run_t"], "layout_best_r_rad": b["r"],
                "layout_best_cam2_x_m": best["cam2"][0], "layout_best_cam2_z_m": best["cam2"][2],
                "layout_best_cam2_yaw_deg": best["cam2"][3]})
    if paper is not None:
        p = paper[method]
        fig.update({"layout_paper_t_m": p["t"], "layout_paper_tx_m": p["tx"],
                    "layout_paper_worst_run_t_m": p["worst_run_t"], "layout_paper_r_rad": p["r"],
                    "layout_paper_rank": paper["rank"]})
        if p["t"] > 0:
            fig["layout_best_vs_paper_t_ratio"] = b["t"] / p["t"]
        print("  best: %s (rank 1), t %.6f m; the paper's placement: rank %d, t %.6f m"
              % (best["name"], b["t"], paper["rank"], p["t"]))
    fig = {k: v for k, v in fig.items() if isinstance(v, (int, float)) and v == v}
    with open(argv[2], "w") as f:
        json.dump(fig, f, indent=2)
        f.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
