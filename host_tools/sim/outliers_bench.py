#!/usr/bin/env python3
"""outliers_bench.py CLEAN_JSON ROBUST_JSON PLAIN_JSON OUT_JSON - `make bench` section outliers.

Reads three `rigpose-sim --json` outputs of the same runs (clean; with --outliers; with
--outliers --plain-update), prints each method's mean errors and their ratios to the clean run,
and writes one flat JSON object: outliers_<frac>_<method>_<col>_ratio (the defaults: 1-point
RANSAC and the re-find) and outliers_<frac>_plain_<method>_<col>_ratio (the plain gated update),
outliers_frac and outliers_runs. Issue 14's target: every ratio of the defaults within 1.5.
"""
import json
import sys

COLS = ("tx", "ty", "tz", "alpha", "beta", "gamma")


def rows(path):
    doc = json.load(open(path))
    return doc, {r["method"]: r for r in doc["rows"]}


def main(argv):
    if len(argv) != 5:
        sys.stderr.write(__doc__)
        return 2
    _, clean = rows(argv[1])
    doc, robust = rows(argv[2])
    _, plain = rows(argv[3])
    frac = doc.get("outliers", 0.0)
    tag = "%d" % round(100 * frac)
    fig = {"outliers_frac": frac, "outliers_runs": doc["runs"]}
    print("\n== outliers: %g of every camera's features uniform pixels, anew every frame; %d runs x "
          "%d frames, seed %d; mean absolute error (m, rad) and ratio to the clean runs ==" %
          (frac, doc["runs"], doc["frames"], doc["seed"]))
    print("  %-32s" % "" + "".join("%10s" % c for c in COLS))
    for m in clean:
        for label, src, key in (("clean", clean, None), ("outliers, defaults", robust, ""),
                                ("outliers, plain update", plain, "plain_")):
            print("  %-32s" % ("%s %s" % (m, label)) +
                  "".join("%10.6f" % src[m][c] for c in COLS))
            if key is not None:
                ratio = [src[m][c] / clean[m][c] for c in COLS]
                print("  %-32s" % "  ratio" + "".join("%10.2f" % r for r in ratio))
                for c, r in zip(COLS, ratio):
                    fig["outliers_%s_%s%s_%s_ratio" % (tag, key, m, c)] = round(r, 3)
    print("  target (issue 14): every ratio of the defaults within 1.5")
    with open(argv[4], "w") as f:
        json.dump(fig, f, indent=1, sort_keys=True)
        f.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
