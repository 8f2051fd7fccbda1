#!/usr/bin/env bash
# test_sim_nees.sh - the consistency of gc's published pose covariance on a seed its tuning
# never saw (issue 16: mean NEES within [0.5, 2] x 6 dof), run by `make test`.
# rigpose-sim scores every frame a method stepped OK by e^T C^-1 e, e = truth [-] estimate in
# the pose chart, C = rp_estimate_t.cov (the filter's covariance plus gc's consider terms for
# the map's correlated errors, rp_vo_gc.h step 5). Those terms were set on seed 1 (Table 1);
# NEES_SEED (host_tools/sim/sim.mk, chosen after them) is fresh. With the terms zeroed
# (scale_sigma, trans_drift_sigma, rot_drift_sigma) the same run gives 446, so the test can fail.
set -u
BUILD=${BUILD:-build}
. "$(dirname "$0")/../../tests/script_env.sh"
: "${NEES_SEED:?set by host_tools/sim/sim.mk: run through make}"
pass=0; fail=0
ok() { pass=$((pass + 1)); echo "[       OK ] $1"; }
bad() { fail=$((fail + 1)); echo "[  FAILED  ] $1"; }

if "$REL/rigpose-sim" --methods gc --runs 20 --seed "$NEES_SEED" --json > "$TMP/nees.json" \
       2>"$TMP/err.log" &&
   python3 - "$TMP/nees.json" <<'PYEOF'
import json, sys
doc = json.load(open(sys.argv[1]))
r = {x["method"]: x for x in doc["rows"]}["gc"]
print("gc, seed %d, %d runs: mean NEES %.2f (translation %.2f, rotation %.2f) over %d frames, "
      "%d not positive definite" % (doc["seed"], doc["runs"], r["nees"], r["nees_t"],
                                    r["nees_r"], r["nees_frames"], r["nees_not_pd"]))
assert r["nees_frames"] >= 0.9 * doc["runs"] * (doc["frames"] - 1), "too few frames scored"
assert r["nees_not_pd"] == 0
assert 0.5 * 6 <= r["nees"] <= 2.0 * 6, "NEES outside [3, 12]"
PYEOF
then ok "gc: published covariance consistent on a fresh seed (mean NEES within [3, 12])"
else cat "$TMP/err.log"; bad "gc NEES on a fresh seed"; fi

echo "[  PASSED  ] $pass test(s)."
if [ $fail -ne 0 ]; then echo "[  FAILED  ] $fail test(s)."; exit 1; fi
