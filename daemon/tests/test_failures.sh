#!/usr/bin/env bash
# test_failures.sh BUILD - every failure class of the rigpose daemon, as an operator sees it:
# for each, the exit code daemon/README.md documents and the message naming the file (and line)
# or the camera. Runs the release daemon on replay folders and configurations it writes, LCM on
# memq:// (in-process: nothing leaves this machine). Each run is bounded by `timeout` (a hang,
# e.g. a FIFO opened as an image, fails the case instead of the test run).
#   configuration (exit 2): a missing file, a key error, 100,000 nested levels under meta:, a
#     second document, a distortion that folds inside the image, a terminal escape in a value;
#   LCM (exit 3): an unknown provider; estimator (exit 5): a stereo pair without baseline;
#   source open (exit 4): frames.csv missing, a folder, a bad header; a v4l2 device that does
#     not exist, a file that is not a video device;
#   while running (exit 0): one camera's missing image (only that camera reported missing, the
#     set still published), images of the wrong size, a FIFO and a folder listed as images, a
#     100 KB comment, a comment
#     whose tail is a row, a row longer than the limit, time going backwards, blank images (the
#     estimator's failure said once);
#   source failed for good (exit 6): 60 malformed rows in a row, the messages rate-limited.
set -u
BUILD=${1:?usage: test_failures.sh BUILD}
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
cd "$ROOT"
DAEMON=$BUILD/release/rigpose
TMP=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$TMP"' EXIT
pass=0; fail=0
ok()  { echo "ok   $1"; pass=$((pass + 1)); }
bad() { echo "FAIL $1"; fail=$((fail + 1)); }

W=160; H=120
pgm() { { printf 'P5\n%d %d\n255\n' $W $H; head -c $((W * H)) /dev/urandom; } >"$1"; }

# A replay folder $1 with N rows of two cameras (c0_K.pgm, c1_K.pgm), 33 ms apart, and its
# configuration rig.yaml (stereo2 on two 160x120 cameras).
make_replay() { # dir rows
  local d=$1 n=$2
  mkdir -p "$d"
  echo "utime_us,cam0,cam1" >"$d/frames.csv"
  for k in $(seq 0 $((n - 1))); do
    pgm "$d/c0_$k.pgm"; pgm "$d/c1_$k.pgm"
    echo "$((1000 + 33333 * k)),c0_$k.pgm,c1_$k.pgm" >>"$d/frames.csv"
  done
  cat >"$d/rig.yaml" <<EOF
version: 1
source: {kind: replay, replay_index: frames.csv}
cameras:
  - {name: left, device: cam0, width: $W, height: $H, intrinsics: [200, 200, 80, 60],
     position: [0, 0, 0], angles: [0, 0, 0]}
  - {name: right, device: cam1, width: $W, height: $H, intrinsics: [200, 200, 80, 60],
     position: [0.1, 0, 0], angles: [0, 0, 0]}
estimator: {method: stereo2, pairs: [[left, right]]}
lcm: {url: "memq://"}
EOF
}

# run NAME CONFIG [args...]: the daemon with a 60 s bound; $rc, $TMP/NAME.out, $TMP/NAME.err
run() {
  local name=$1 cfg=$2; shift 2
  timeout 60 "$DAEMON" --config "$cfg" --fast "$@" >"$TMP/$name.out" 2>"$TMP/$name.err"
  rc=$?
}
has() { grep -qF -- "$2" "$TMP/$1.err"; }           # stderr of run NAME holds the text
has_out() { grep -qF -- "$2" "$TMP/$1.out"; }
poses() { sed -nE 's/^rigpose: ([0-9]+) poses published.*/\1/p' "$TMP/$1.out"; }
show() { echo "     exit $rc; stderr: $(head -c 600 "$TMP/$1.err" | tr '\n' '|')"; }
check() { # name cond description
  if [ "$2" = 1 ]; then ok "$1: $3"; else bad "$1: $3"; show "$1"; fi
}
t() { if eval "$1"; then echo 1; else echo 0; fi; }

# ---- configuration: exit 2 --------------------------------------------------------------------
R=$TMP/base; make_replay "$R" 5
run nofile "$TMP/none.yaml"
check nofile "$(t '[ $rc -eq 2 ] && has nofile "$TMP/none.yaml:0: (file): No such file or directory"')" \
  "missing configuration file: exit 2 naming the file"
sed 's/intrinsics: \[200, 200, 80, 60\],$/intrinsics: [200, 200, 80],/' "$R/rig.yaml" >"$R/key.yaml"
run key "$R/key.yaml"
check key "$(t '[ $rc -eq 2 ] && has key "$R/key.yaml:4: cameras[0].intrinsics: expected 4 numbers"')" \
  "bad key: exit 2, FILE:LINE: KEY"
{ cat "$R/rig.yaml"; printf 'meta: '; head -c 100000 /dev/zero | tr '\0' '['; echo; } >"$R/deep.yaml"
t0=$(date +%s%N); run deep "$R/deep.yaml"; ms=$(( ($(date +%s%N) - t0) / 1000000 ))
check deep "$(t '[ $rc -eq 2 ] && [ $ms -lt 5000 ] && has deep "$R/deep.yaml:10: (yaml): nested deeper than 32 levels"')" \
  "100,000 levels under meta: exit 2 in $ms ms"
{ cat "$R/rig.yaml"; echo "---"; cat "$R/rig.yaml"; } >"$R/two.yaml"
run two "$R/two.yaml"
check two "$(t '[ $rc -eq 2 ] && has two "$R/two.yaml:10: (yaml): a second document"')" \
  "a second YAML document: exit 2"
sed '0,/angles: \[0, 0, 0\]}/! s/position: \[0.1, 0, 0\], angles: \[0, 0, 0\]}/position: [0.1, 0, 0], angles: [0, 0, 0], distortion: [99, 0, 0, 0, 0]}/' \
    "$R/rig.yaml" >"$R/k99.yaml"
run k99 "$R/k99.yaml"
check k99 "$(t '[ $rc -eq 2 ] && has k99 "cameras[1].distortion: stretches the image"')" \
  "distortion k1 = 99: exit 2 naming cameras[1].distortion"
sed 's/pairs: \[\[left, right\]\]/pairs: [[left, "r\\e]0;pwned\\a\\e[2J"]]/' "$R/rig.yaml" >"$R/esc.yaml"
run esc "$R/esc.yaml"
check esc "$(t '[ $rc -eq 2 ] && ! LC_ALL=C grep -q "[[:cntrl:]]" <(tr -d "\n" <"$TMP/esc.err") && has esc "no camera is named '"'"'r\x1b]0;pwned\x07\x1b[2J'"'"'"')" \
  "terminal escapes in a value: exit 2, printed as \\xNN"

# ---- LCM: exit 3 ------------------------------------------------------------------------------
run lcm "$R/rig.yaml" --lcm-url 'bogus://nowhere'
check lcm "$(t '[ $rc -eq 3 ] && has lcm "LCM: cannot use '"'"'bogus://nowhere'"'"'"')" \
  "unknown LCM provider: exit 3 naming the URL"

# ---- estimator: exit 5 ------------------------------------------------------------------------
sed 's/position: \[0.1, 0, 0\]/position: [0, 0, 0]/' "$R/rig.yaml" >"$R/nobase.yaml"
run nobase "$R/nobase.yaml"
check nobase "$(t '[ $rc -eq 5 ] && has nobase "rigpose: $R/nobase.yaml: method stereo2 refused the configuration: degenerate geometry"')" \
  "a stereo pair without baseline: exit 5 naming the method and why"

# ---- source open: exit 4 ----------------------------------------------------------------------
mkdir -p "$TMP/empty"; sed 's#replay_index: frames.csv#replay_index: empty/frames.csv#' "$R/rig.yaml" \
    >"$TMP/noidx.yaml"
run noidx "$TMP/noidx.yaml"
check noidx "$(t '[ $rc -eq 4 ] && has noidx "rigpose: $TMP/noidx.yaml: camera source: device or file could not be opened: $TMP/empty/frames.csv: No such file or directory"')" \
  "frames.csv missing: exit 4 naming it"
mkdir -p "$TMP/dir/frames.csv"; sed 's#replay_index: frames.csv#replay_index: dir#' "$R/rig.yaml" \
    >"$TMP/dir.yaml"
run dir "$TMP/dir.yaml"
check dir "$(t '[ $rc -eq 4 ] && has dir "$TMP/dir/frames.csv: is a directory"')" \
  "frames.csv a folder: exit 4 naming it"
H2=$TMP/hdr; make_replay "$H2" 2; sed -i '1s/.*/time,cam0,cam1/' "$H2/frames.csv"
run hdr "$H2/rig.yaml"
check hdr "$(t '[ $rc -eq 4 ] && has hdr "$H2/frames.csv:1: header must be utime_us,cam0,cam1"')" \
  "bad frames.csv header: exit 4 naming file:1"
v4l2_cfg() { # device
  cat <<EOF
version: 1
source: {kind: v4l2, timeout_ms: 200}
cameras:
  - {name: front, device: $1, width: 640, height: 480, intrinsics: [500, 500, 320, 240],
     position: [0, 0, 0], angles: [0, 0, 0]}
estimator: {method: cam1, cams: [front]}
lcm: {url: "memq://"}
EOF
}
v4l2_cfg /dev/rigpose-video7 >"$TMP/v7.yaml"
run v7 "$TMP/v7.yaml"
check v7 "$(t '[ $rc -eq 4 ] && has v7 "/dev/rigpose-video7: cannot open: No such file or directory"')" \
  "missing /dev/video device: exit 4 naming it"
v4l2_cfg /dev/null >"$TMP/vnull.yaml"
run vnull "$TMP/vnull.yaml"
check vnull "$(t '[ $rc -eq 4 ] && has vnull "/dev/null: not a V4L2 device"')" \
  "/dev/null as a camera: exit 4, not a V4L2 device"

# ---- while running: said, the run goes on (exit 0) --------------------------------------------
M=$TMP/miss; make_replay "$M" 6; rm "$M/c1_3.pgm"
run miss "$M/rig.yaml"
check miss "$(t '[ $rc -eq 0 ] && [ "$(poses miss)" = 6 ] && has miss "set 3: camera source: degraded set: $M/frames.csv:5: camera 1: $M/c1_3.pgm: No such file or directory" && has_out miss "set 3: camera 1 (right): missing" && has_out miss "set 4: camera 1 (right): ok again" && ! has_out miss "camera 0 (left)"')" \
  "one missing image: exit 0, 6 of 6 sets published, only camera 1 missing, file:line named"
TR=$TMP/truth; make_replay "$TR" 4
printf 'utime_us,tx,ty,tz,alpha,beta,gamma\n1000,0,0,0,0,0,0\n34333,0,0,x,0,0,0\n66666,0,0,0,0,0,0\n99999,0,0,0,0,0,0\n' >"$TR/truth.csv"
run truth "$TR/rig.yaml"
check truth "$(t '[ $rc -eq 0 ] && [ "$(poses truth)" = 4 ] && has truth "set 1: camera source: degraded set: $TR/truth.csv:3: want utime_us and 6 numbers: row skipped, set 1 has no truth" && has truth "1 sets delivered degraded for a reason"')" \
  "a malformed truth.csv row: exit 0, 4 of 4 sets published, the row named, only its truth skipped"
F=$TMP/fifo; make_replay "$F" 4; rm "$F/c0_1.pgm" "$F/c1_2.pgm"; mkfifo "$F/c0_1.pgm"; mkdir "$F/c1_2.pgm"
run fifo "$F/rig.yaml"
check fifo "$(t '[ $rc -eq 0 ] && [ "$(poses fifo)" = 4 ] && has fifo "$F/frames.csv:3: camera 0: $F/c0_1.pgm: is a FIFO, not a regular file" && has fifo "$F/frames.csv:4: camera 1: $F/c1_2.pgm: is a directory"')" \
  "a FIFO and a folder as images: no hang, exit 0, each named"
C=$TMP/comment; make_replay "$C" 5
{ head -3 "$C/frames.csv"; printf '#'; head -c 100000 /dev/zero | tr '\0' 'c'; echo;
  printf '#'; head -c 1598 /dev/zero | tr '\0' 'c'; echo "9000,c0_0.pgm,c1_0.pgm"; tail -n +4 "$C/frames.csv"; } \
  >"$C/f2" && mv "$C/f2" "$C/frames.csv"
run comment "$C/rig.yaml"
check comment "$(t '[ $rc -eq 0 ] && [ "$(poses comment)" = 5 ] && [ ! -s "$TMP/comment.err" ]')" \
  "a 100 KB comment and a comment whose tail is a row: exit 0, 5 poses from 5 rows, nothing said"
L=$TMP/long; make_replay "$L" 4
{ head -3 "$L/frames.csv"; printf '50000,'; head -c 2000 /dev/zero | tr '\0' 'a'; echo ',x.pgm';
  tail -n +4 "$L/frames.csv"; } >"$L/f2" && mv "$L/f2" "$L/frames.csv"
run long "$L/rig.yaml"
check long "$(t '[ $rc -eq 0 ] && [ "$(poses long)" = 4 ] && has long "$L/frames.csv:4: line longer than "')" \
  "a 2,000-character row: refused naming file:4, the other 4 sets published"
S=$TMP/size; make_replay "$S" 3
sed -i "0,/width: $W, height: $H, intrinsics: \[200, 200, 80, 60\]/! s/width: $W, height: $H, intrinsics: \[200, 200, 80, 60\]/width: 120, height: 100, intrinsics: [200, 200, 60, 50]/" "$S/rig.yaml"
run size "$S/rig.yaml"
check size "$(t '[ $rc -eq 0 ] && [ "$(poses size)" = 3 ] && has size "$S/frames.csv:2: camera 1: $S/c1_0.pgm: 160x120, configured 120x100" && has_out size "set 0: camera 1 (right): missing" && ! has_out size "camera 0 (left)"')" \
  "camera 1's images of the wrong size: that camera missing, named with file:line and sizes"
# On a rendered room (rigpose-render, when built: make test builds it), the set missing one
# camera's image still tracks on the other five.
if [ -x "$BUILD/release/rigpose-render" ]; then
  "$BUILD/release/rigpose-render" --out "$TMP/room" --frames 12 --width 320 --height 240 \
      --face-px 256 --ss 1 >/dev/null 2>&1
  rm -f "$TMP/room/cam3/000005".*
  run room "$TMP/room/rig.yaml" --lcm-url memq://
  check room "$(t '[ $rc -eq 0 ] && [ "$(poses room)" = 12 ] && has room "$TMP/room/frames.csv:7: camera 3: $TMP/room/cam3/000005.png: No such file" && grep -Eq "^ +5 .* TRACK" "$TMP/room.out" && has_out room "set 5: camera 3 (cam4): missing" && has_out room "set 6: camera 3 (cam4): ok again"')" \
    "rendered room, camera 3's image of set 5 missing: set 5 still TRACK on the other five, 12 poses"
else
  echo "skip rendered room: $BUILD/release/rigpose-render not built"
fi
B=$TMP/back; make_replay "$B" 4; sed -i '4s/^[0-9]*,/500,/' "$B/frames.csv"
run back "$B/rig.yaml"
check back "$(t '[ $rc -eq 0 ] && [ "$(poses back)" = 3 ] && has back "$B/frames.csv:4: utime_us 500 not after 34333"')" \
  "time going backwards: the row refused naming file:line"

Z=$TMP/blank; make_replay "$Z" 20
for f in "$Z"/c*.pgm; do { printf 'P5\n%d %d\n255\n' $W $H; head -c $((W * H)) /dev/zero; } >"$f"; done
run blank "$Z/rig.yaml"
n_est=$(grep -c "estimator: step failed" "$TMP/blank.out")
check blank "$(t '[ $rc -eq 0 ] && [ "$(poses blank)" = 20 ] && [ $n_est = 1 ] && has_out blank "rigpose: set 0: estimator: step failed: " && has_out blank "rigpose: set 0: estimator: LOST"')" \
  "20 blank sets: the estimator's failure said once ($n_est line), 20 poses published"

# ---- failed for good: exit 6 ------------------------------------------------------------------
G=$TMP/good; make_replay "$G" 2
for k in $(seq 1 60); do echo "$((200000 + k)),c0_0.pgm" >>"$G/frames.csv"; done
run gone "$G/rig.yaml"
n_lines=$(grep -c "camera source: no usable format" "$TMP/gone.err")
check gone "$(t '[ $rc -eq 6 ] && has gone "camera source failed for good (51 failing grabs in a row), the last: no usable format, or a malformed file: $G/frames.csv:54: want utime_us and 2 image paths" && has gone "$G/frames.csv:4: want utime_us" && [ $n_lines -le 10 ] && has gone "51 failed grabs"')" \
  "60 malformed rows: exit 6 naming file:line, $n_lines of 51 failures printed (rate limit)"

echo
if [ $fail -eq 0 ]; then echo "[  PASSED  ] $pass test(s)."; exit 0; fi
echo "[  PASSED  ] $pass test(s)."
echo "[  FAILED  ] $fail test(s)."
exit 1
