#!/usr/bin/env bash
# test_e2e.sh - short end-to-end runs from rendered pixels (run by `make test`): 1 and 2 at
# 320x240, 25 frame sets of the paper's motion through the core's image pipeline, stereo4 and
# gc with loose bounds on the mean tx error (a broken front end or a jumping estimator is off by
# centimetres):
#   1. the shell scene: gc 4 mm (measured 2.3 mm; 3.6 mm before gc's metric scale step, whose
#      map scale then came from the assumed depth), stereo4 0.5 mm (measured 0.010 mm; before
#      rp_vo_stereo's widened retry it jumped by ~1 cm here);
#   2. the points scene (rp_sim's own points as discs): gc 3 mm (measured 1.3 mm; 2.5 mm
#      before), stereo4 1 mm (measured 0.092 mm).
# and the tracks against the scene's truth one frame after birth (--check-track): shell 0.2 px
# (measured 0.089 / 0.087 px for gc's / stereo4's cameras), points 1.0 px (0.476 / 0.406 px).
# 3. the moving object (--moving-object: a sphere covering 30 % of cam1's view that moves with
#    the rig, host_tools/render/README.md), 640x480, 60 frame sets of run 0: stereo4's mean tx
#    error within 10x the same frames' without the object (measured 4.6x; 54.6x when 1-point
#    RANSAC's rescue took the object and the scene together: rp_ekf1pt.h, step 2b).
#    The issue's target, 1.5x, is not met (docs/results.md).
# 4. the moving object in run 7, frames 0-3: stereo4's mean tx error within 0.1 mm (measured
#    0.008 mm; 0.24 mm before RANSAC's pose was refined with Cauchy weights on the inliers' own
#    scale, the object's near points inside RANSAC's gate drawing the start, rp_vo_stereo.h
#    step 2; 0.97 mm, with 8 mm in ty at frame 2, before a re-found pose was also judged by its
#    MSAC cost: the update had taken the object in the front pair with the rear pair's
#    features a pixel off, step 3).
# RP_E2E_BIN (exported by e2e.mk) is the program; default build/release/rigpose-e2e.
set -u
bin=${RP_E2E_BIN:-build/release/rigpose-e2e}
pass=0
fail=0
run() {
  local what=$1
  shift
  if "$bin" --methods gc,stereo4 --runs 1 --frames 25 --width 320 --height 240 --quiet "$@"; then
    echo "[       OK ] $what"
    pass=$((pass + 1))
  else
    echo "[  FAILED  ] $what"
    fail=$((fail + 1))
  fi
}
run "shell scene: gc and stereo4 within their bounds" --face-px 512 --check gc=0.004,stereo4=0.0005 \
  --check-track 0.2
run "points scene: gc and stereo4 within their bounds" --points --check gc=0.003,stereo4=0.001 \
  --check-track 1.0
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
tx_of() { # tx_of FILE PREFIX: stereo4's mean tx error from a --json-out file
  grep -o "\"$2stereo4_tx_m\": [0-9.eE+-]*" "$1" | awk '{print $2}'
}
what="moving object: stereo4 within 10x of the static scene"
if "$bin" --methods stereo4 --runs 1 --frames 60 --ss 1 --no-sim-ref --quiet \
     --json-out "$tmp/static.json" >/dev/null &&
   "$bin" --methods stereo4 --runs 1 --frames 60 --ss 1 --no-sim-ref --quiet --moving-object \
     --json-out "$tmp/object.json" >/dev/null &&
   awk -v s="$(tx_of "$tmp/static.json" render_)" \
       -v o="$(tx_of "$tmp/object.json" render_moving_)" \
     'BEGIN { printf "stereo4 tx: static %.3g m, moving object %.3g m (%.1fx)\n", s, o, o / s;
              exit !(s > 0 && o > 0 && o <= 10 * s) }'; then
  echo "[       OK ] $what"
  pass=$((pass + 1))
else
  echo "[  FAILED  ] $what"
  fail=$((fail + 1))
fi
what="moving object, run 7 frames 0-3: stereo4 within 0.1 mm"
if "$bin" --methods stereo4 --first-run 7 --runs 1 --frames 4 --ss 1 --no-sim-ref --quiet \
     --moving-object --check stereo4=0.0001; then
  echo "[       OK ] $what"
  pass=$((pass + 1))
else
  echo "[  FAILED  ] $what"
  fail=$((fail + 1))
fi
if [ "$fail" -eq 0 ]; then
  echo "[  PASSED  ] $pass test(s)."
else
  echo "[  FAILED  ] $fail test(s), $pass passed."
  exit 1
fi
