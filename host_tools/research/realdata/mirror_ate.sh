#!/usr/bin/env bash
# mirror_ate.sh - issue 14 item 8: rigpose's ATE on each shared clip and on its mirror image
# (rigpose-realdata --mirror: cameras swapped, images flipped left-right, calibration and truth
# mirrored; rp_mirror.hpp), with the core's default settings. Prints one line per clip and
# exits 1 unless every mirrored ATE is within TOL (default 10 %) of the original's.
# Part of `make test` (about a minute under ASan + UBSan); the mirroring itself is tested
# exactly by test_realdata_conv. A clip not in the data folder is skipped.
#   usage: mirror_ate.sh [TOL_PERCENT]     (RP_REALDATA_BIN, RIGPOSE_DATA as test_realdata.sh)
set -u
root=$(cd "$(dirname "$0")/../../.." && pwd)
bin=${RP_REALDATA_BIN:-$root/build/release/rigpose-realdata}
data=${RIGPOSE_DATA:-$root/../shared/data}
tol=${1:-10}
bad=0; n=0
for clip in kitti00_000-099 kitti_raw_0926_0005_000-090 euroc_mh01_000-149; do
  dir=$data/$clip
  [ -d "$dir" ] || { echo "[  SKIPPED ] $clip: not in $data"; continue; }
  fmt=--kitti; [ "${clip#euroc}" != "$clip" ] && fmt=--euroc
  ate() { "$bin" "$fmt" "$dir" --quiet "$@" 2>/dev/null | sed -n 's/^| ATE (RMSE, no alignment) | \([0-9.]*\) m |$/\1/p'; }
  a=$(ate); m=$(ate --mirror)
  if [ -z "$a" ] || [ -z "$m" ]; then echo "[  FAILED  ] $clip: no ATE (run broke)"; bad=$((bad + 1)); continue; fi
  n=$((n + 1))
  if awk -v a="$a" -v m="$m" -v t="$tol" 'BEGIN { d = (m - a) / a * 100; printf "%s ATE %.4f m, mirror image %.4f m: %+.1f %%", "", a, m, d; exit !(d <= t && d >= -t) }' >/tmp/mirror_ate.$$; then
    echo "[       OK ] $clip:$(cat /tmp/mirror_ate.$$) (within $tol %)"
  else
    echo "[  FAILED  ] $clip:$(cat /tmp/mirror_ate.$$) (beyond $tol %)"; bad=$((bad + 1))
  fi
  rm -f /tmp/mirror_ate.$$
done
echo "mirror_ate: $n clip(s), $bad beyond $tol % or broken"
[ $bad -eq 0 ]
