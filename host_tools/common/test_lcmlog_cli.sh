#!/usr/bin/env bash
# test_lcmlog_cli.sh - rigpose-eval and `rigpose-log replay` on broken LCM logs (make test).
# A log written by the lcm Python package (10 rigpose.pose_t with truth, 4 sets of 2
# rigpose.image_t, interleaved), then three copies of it broken as issue 18 found them:
#   huge.log     event 5's header claims 0x7fffffff bytes of data (liblcm: SIGSEGV)
#   trunc.log    cut 30 bytes into event 7
#   garbage.log  100 bytes of garbage (with a false sync word) before event 6
# Each tool on each: exit 1, one line on stderr naming the file and the event's byte offset,
# nothing written. With --tolerant: the garbage is skipped with one warning saying how many bytes,
# and the result is that of the clean log (same evaluation, same replay folder).
# Also negsize.log: a well-formed log whose image_t claims size -1 (lcm-gen's decoder copies
# (size_t)-1 bytes): rigpose-log replay counts it as not an image and replays the rest.
# `rigpose-log mcap` (rigpose-view --lcm-log, Python: rp_lcmlog.py; PyPI lcm's EventLog died with
# SIGSEGV on huge.log) the same: one line with the offset, exit 1, no MCAP; --tolerant converts.
set -u
eval_bin=${RP_EVAL_BIN:-build/release/rigpose-eval}
view_bin=${RP_VIEW_BIN:-build/release/rigpose-view}
log_bin=${RP_LOG_BIN:-build/release/rigpose-log}
work=${RP_LCMLOG_WORK:-build/common/work}
PY=${PY:-.venv/bin/python}
export PYTHONPATH=${RP_LCM_PY:-$(dirname "$log_bin")/../lcmgen/python}
rm -rf "$work" && mkdir -p "$work"
pass=0; fail=0
check() { if eval "$2"; then echo "[       OK ] $1"; pass=$((pass+1)); else echo "[  FAILED  ] $1"; fail=$((fail+1)); fi; }

"$PY" - "$work" <<'PYEOF' || { echo "[  FAILED  ] 1 test(s): could not write the logs"; exit 1; }
import os, random, struct, sys, lcm
from rigpose import pose_t, image_t
w = sys.argv[1]
good = os.path.join(w, "good.log")
log = lcm.EventLog(good, "w", overwrite=True)
seq = 0
for i in range(10):
    p = pose_t()
    p.utime = 1000000 + 100000 * i
    p.seq = i
    p.frame = i
    p.position = [0.01 * i, 0.002 * i, 0.0]
    p.quaternion = [1.0, 0.0, 0.0, 0.0]
    p.n_cams = 2
    p.has_truth = True
    p.truth = [0.01 * i, 0.002 * i, 0.0, 0.0, 0.0, 0.0]
    log.write_event(p.utime, "RIGPOSE_POSE", p.encode())
    if i % 2 == 0 and seq < 4:
        for cam in range(2):
            m = image_t()
            m.utime = p.utime
            m.seq = seq
            m.cam = cam
            m.width, m.height = 8, 6
            m.size = 48
            m.data = bytes((seq * 16 + cam * 5 + k) % 256 for k in range(48))
            log.write_event(p.utime, "RIGPOSE_IMAGE", m.encode())
        seq += 1
log.close()
raw = open(good, "rb").read()
at, o = [], 0
while o < len(raw):  # event offsets
    at.append(o)
    cl, dl = struct.unpack(">ii", raw[o + 20:o + 28])
    o += 28 + cl + dl
assert o == len(raw) and len(at) == 18, (o, len(raw), len(at))
def put(name, data, off):
    open(os.path.join(w, name + ".log"), "wb").write(data)
    open(os.path.join(w, name + ".off"), "w").write(str(off))
b = bytearray(raw); b[at[5] + 24:at[5] + 28] = struct.pack(">I", 0x7fffffff)
put("huge", bytes(b), at[5])
put("trunc", raw[:at[7] + 30], at[7])
rng = random.Random(18)
junk = bytes(rng.randrange(256) for _ in range(40)) + b"\xed\xa1\xda\x01" + bytes(56)
put("garbage", raw[:at[6]] + junk + raw[at[6]:], at[6])
log = lcm.EventLog(os.path.join(w, "negsize.log"), "w", overwrite=True)
for seq in range(3):
    m = image_t()
    m.utime, m.seq, m.cam, m.width, m.height, m.size = 1000 * seq, seq, 0, 4, 2, 8
    m.data = bytes(range(8))
    e = bytearray(m.encode())
    if seq == 1:
        e[-12:-8] = struct.pack(">i", -1)  # size field: 4 bytes before the 8 of data
    log.write_event(m.utime, "RIGPOSE_IMAGE", bytes(e))
log.close()
PYEOF

# Each tool on each broken log, strict: exit 1, one line with the offset, nothing written.
for kind in huge trunc garbage; do
  off=$(cat "$work/$kind.off")
  "$eval_bin" "$work/$kind.log" > "$work/eval_$kind.out" 2> "$work/eval_$kind.err"; rc=$?
  cat "$work/eval_$kind.err"
  check "rigpose-eval $kind.log: exit 1 ($rc), one line naming offset $off" \
    '[ $rc -eq 1 ] && [ $(wc -l < "$work/eval_$kind.err") -eq 1 ] && grep -q "^rigpose-eval: $work/$kind.log: offset $off: " "$work/eval_$kind.err"'
  "$log_bin" replay "$work/$kind.log" --dir "$work/dir_$kind" > /dev/null 2> "$work/log_$kind.err"; rc=$?
  cat "$work/log_$kind.err"
  check "rigpose-log replay $kind.log: exit 1 ($rc), one line naming offset $off, no folder" \
    '[ $rc -eq 1 ] && [ $(wc -l < "$work/log_$kind.err") -eq 1 ] && grep -q "^rigpose-log: $work/$kind.log: offset $off: " "$work/log_$kind.err" && [ ! -e "$work/dir_$kind" ]'
done
check "the 0x7fffffff length is named" 'grep -q "data 2147483647" "$work/eval_huge.err"'
check "the truncation is named" 'grep -q "truncated" "$work/eval_trunc.err"'
check "the garbage is named" 'grep -q "no event header" "$work/eval_garbage.err"'

# --tolerant: past the garbage, the clean log's result.
"$eval_bin" "$work/good.log" > "$work/eval_good.out" 2>&1; rc_good=$?
"$eval_bin" --tolerant "$work/garbage.log" > "$work/eval_tol.out" 2> "$work/eval_tol.err"; rc=$?
cat "$work/eval_tol.err"
check "rigpose-eval --tolerant garbage.log: exit 0, 100 bytes skipped, the clean log's 10 poses" \
  '[ $rc_good -eq 0 ] && [ $rc -eq 0 ] && grep -q "skipped 100 bytes to the next event at offset" "$work/eval_tol.err" && diff <(sed 1d "$work/eval_good.out") <(sed 1d "$work/eval_tol.out") > /dev/null && grep -q "(10 poses)" "$work/eval_tol.out"'
"$log_bin" replay "$work/good.log" --dir "$work/dir_good" 2> /dev/null; rc_good=$?
"$log_bin" replay --tolerant "$work/garbage.log" --dir "$work/dir_tol" 2> "$work/log_tol.err"; rc=$?
cat "$work/log_tol.err"
check "rigpose-log replay --tolerant garbage.log: exit 0, 100 bytes skipped, the clean log's folder" \
  '[ $rc_good -eq 0 ] && [ $rc -eq 0 ] && grep -q "skipped 100 bytes" "$work/log_tol.err" && [ $(($(wc -l < "$work/dir_tol/frames.csv") - 1)) -eq 4 ] && diff -r "$work/dir_good" "$work/dir_tol" > /dev/null'
"$eval_bin" --tolerant "$work/trunc.log" > /dev/null 2> "$work/eval_tol_trunc.err"; rc=$?
check "rigpose-eval --tolerant trunc.log: exit 0, the cut tail skipped and said" \
  '[ $rc -eq 0 ] && grep -q "skipped the last" "$work/eval_tol_trunc.err"'

# rigpose-log mcap: rigpose-view reads the log with rp_lcmlog.py.
if [ -x "$view_bin" ]; then
  for kind in huge trunc garbage; do
    off=$(cat "$work/$kind.off")
    "$log_bin" mcap "$work/$kind.log" "$work/$kind.mcap" --quiet > /dev/null 2> "$work/mcap_$kind.err"; rc=$?
    cat "$work/mcap_$kind.err"
    check "rigpose-log mcap $kind.log: exit 1 ($rc), one line naming offset $off, no MCAP" \
      '[ $rc -eq 1 ] && [ $(wc -l < "$work/mcap_$kind.err") -eq 1 ] && grep -q ": $work/$kind.log: offset $off: " "$work/mcap_$kind.err" && [ ! -e "$work/$kind.mcap" ]'
  done
  "$log_bin" mcap "$work/garbage.log" "$work/tol.mcap" --tolerant > "$work/mcap_tol.out" 2> "$work/mcap_tol.err"; rc=$?
  cat "$work/mcap_tol.err" "$work/mcap_tol.out"
  check "rigpose-log mcap --tolerant garbage.log: exit 0, 100 bytes skipped, 10 poses and 8 images" \
    '[ $rc -eq 0 ] && grep -q "skipped 100 bytes" "$work/mcap_tol.err" && grep -q "10 poses (last seq 9), 8 images" "$work/mcap_tol.out" && [ -s "$work/tol.mcap" ]'
else
  echo "test_lcmlog_cli: no $view_bin: rigpose-log mcap not checked"
fi

# An image_t with size -1 (lcm-gen's decoder would copy (size_t)-1 bytes).
"$log_bin" replay "$work/negsize.log" --dir "$work/dir_neg" 2> "$work/log_neg.err"; rc=$?
cat "$work/log_neg.err"
check "rigpose-log replay: an image_t of size -1 is not an image, the other 2 sets replayed" \
  '[ $rc -eq 0 ] && grep -q "1 messages on RIGPOSE_IMAGE are not valid images" "$work/log_neg.err" && [ $(($(wc -l < "$work/dir_neg/frames.csv") - 1)) -eq 2 ]'

if [ $fail -eq 0 ]; then echo "[  PASSED  ] $pass test(s)."; else echo "[  FAILED  ] $fail test(s)."; exit 1; fi
