#!/usr/bin/env bash
# test_calib_cli.sh - rigpose-calib as a user runs it (make test), on opencv-doc's stereo set:
#  - stereo mode with a left image whose right partner is missing and a corrupt right image:
#    each is reported on its own line, the rest is calibrated, the YAML is written (exit 0);
#  - rig mode on a frames.csv of the same pairs (--pair cam0,cam1);
#  - bad usage exits 2; the written files load in the daemon's configuration parser
#    (RP_CFG_CHECK, when the platform's parser is built).
set -u
bin=${RP_CALIB_BIN:-build/release/rigpose-calib}
work=${RP_CALIB_WORK:-build/calib/work}/cli
data=/usr/share/doc/opencv-doc/examples/data
rm -rf "$work" && mkdir -p "$work"
pass=0; fail=0
check() { if eval "$2"; then echo "[       OK ] $1"; pass=$((pass+1)); else echo "[  FAILED  ] $1"; fail=$((fail+1)); fi; }
get() { # copy (or gunzip) an opencv-doc image into the work folder
  if [ -f "$data/$1" ]; then cp "$data/$1" "$work/$1"; else gzip -dc "$data/$1.gz" > "$work/$1"; fi
}
for i in 01 02 03 04 05 06 07 08; do get left$i.jpg; done
for i in 01 02 03 04 06 07 08; do get right$i.jpg; done      # right05 missing
head -c 3000 "$work/right07.jpg" > "$work/right07.tmp" && mv "$work/right07.tmp" "$work/right07.jpg"
echo "not a jpeg" > "$work/right08.jpg"                       # corrupt

out=$("$bin" stereo --fix-aspect --left "$work"/left*.jpg --right "$work"/right*.jpg \
      --out "$work/stereo.yaml" 2>&1); rc=$?
echo "$out" | grep -v 'view RMS'
check "stereo: exit 0 despite the bad files" '[ $rc -eq 0 ]'
check "stereo: left05 reported without right partner" 'grep -q "left05.jpg: no right partner" <<<"$out"'
check "stereo: corrupt right08 rejected with a reason" 'grep -q "right08.jpg: rejected: unreadable" <<<"$out"'
check "stereo: truncated right07 rejected" 'grep -q "right07.jpg: rejected" <<<"$out"'
check "stereo: the 5 complete pairs used" 'grep -q ": 5 pairs, RMS" <<<"$out"'
check "stereo: YAML written" '[ -s "$work/stereo.yaml" ] && grep -q "method: stereo2" "$work/stereo.yaml"'

{ echo "utime_us,cam0,cam1"; for i in 01 02 03 04 06; do echo "$i,left$i.jpg,right$i.jpg"; done; } \
  > "$work/frames.csv"
out=$("$bin" rig --fix-aspect --frames "$work/frames.csv" --pair cam0,cam1 --source replay \
      --out "$work/rig.yaml" 2>&1); rc=$?
echo "$out" | grep -v 'view RMS'
check "rig: two columns as a stereo pair, exit 0" '[ $rc -eq 0 ] && grep -q "stereo cam1-cam2: 5 pairs" <<<"$out"'
base=$(sed -n 's/.*baseline \([0-9.]*\) m.*/\1/p' <<<"$out" | head -1)
check "rig: baseline 0.083 +- 0.003 m (25 mm squares), got $base" \
  'awk -v b="$base" "BEGIN{exit !(b > 0.080 && b < 0.086)}"'

"$bin" >/dev/null 2>&1; rc=$?
check "no arguments: usage, exit 2" '[ $rc -eq 2 ]'
"$bin" mono --board 9 x.jpg >/dev/null 2>&1; rc=$?
check "bad --board: exit 2" '[ $rc -eq 2 ]'
"$bin" mono "$work/right08.jpg" > /dev/null 2>&1; rc=$?
check "no usable view: exit 1" '[ $rc -eq 1 ]'

if [ -n "${RP_CFG_CHECK:-}" ]; then
  for y in stereo.yaml rig.yaml; do
    check "$y loads in the daemon's configuration parser" '"$RP_CFG_CHECK" "$work/$y"'
  done
fi
if [ $fail -eq 0 ]; then echo "[  PASSED  ] $pass test(s)."; else echo "[  FAILED  ] $fail test(s)."; exit 1; fi
