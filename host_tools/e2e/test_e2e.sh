#!/usr/bin/env bash
# test_e2e.sh - a short end-to-end run from rendered pixels (run by `make test`): 320x240, 25
# frame sets of the paper's motion through the core's image pipeline, gc with a loose bound on
# the mean tx error, 10 mm (measured 3.6 mm; a broken front end drifts by centimetres). stereo4 is run
# and printed but not bounded yet: from pixels it jumps by ~1 cm at the first gated frame (see
# host_tools/render/README.md, "Known problems"); add stereo4=0.002 to --check once fixed.
# RP_E2E_BIN (exported by e2e.mk) is the program; default build/release/rigpose-e2e.
set -u
bin=${RP_E2E_BIN:-build/release/rigpose-e2e}
if "$bin" --methods gc,stereo4 --runs 1 --frames 25 --width 320 --height 240 --face-px 512 \
    --check gc=0.01; then
  echo "[  PASSED  ] 1 test(s)."
else
  echo "[  FAILED  ] 1 test(s)."
  exit 1
fi
