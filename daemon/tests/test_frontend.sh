#!/usr/bin/env bash
# test_frontend.sh BUILD - front ends as separate processes (issue 17 item 2), on this host only
# (udpm ttl=0, channels tagged with this process's id): four rigpose-frontend processes, one per
# single camera of method gc, and the daemon with source.kind lcm, on a rendered replay
# (rigpose-render, 150 sets at 30 Hz, 320x240) whose frames.csv is restamped on this host's
# CLOCK_MONOTONIC a few seconds ahead and read with source.realtime: live, so that every
# front end delivers each set at its time like a live camera (and one started late joins the
# present).
#   A. every one of the 150 sets gives a pose, equal to the in-process daemon's on the same
#      frames (source replay, --fast) within 1e-9 in every number, with the same flags and
#      features used; lcm-logger records the four features channels meanwhile;
#   B. that recording played back (lcm-logplayer) into a daemon alone gives the same poses again:
#      an estimator change can be tested on a recording without images; in it, each camera's
#      messages count seq 0, 1, ... and FEAT_NEW marks exactly the ids its previous image lacked;
#   B2. the same recording into a daemon with source.sets: latest (no grouping by time): a
#      pose per frame of camera 0 at its time, seq without a gap;
#   C. front end 2 killed (SIGKILL) mid-run: the status channel reports camera 2 gone, poses go
#      on every set from the other three cameras; restarted, it rejoins: camera 2 ok again on the
#      status channel, and poses use its features again;
#   D. stereo4 (the render's own method): two front ends, one per stereo pair (--cameras 0,4 and
#      cam3,cam3b), give the in-process poses too (every configuration here with dormant_retired
#      false: split front ends cannot see the estimator's retired tracks, config/README.md), FEAT_MATCHED marking exactly the ids the pair
#      partner's image of the same time has; a front end given half a pair is refused.
# Prints the distributed run's latency (frame -> pose, daemon --stats-json) for the record.
set -u
BUILD=${1:?usage: test_frontend.sh BUILD}
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
cd "$ROOT"
REL=$BUILD/release
PY=${PY:-.venv/bin/python}
export PYTHONPATH=$BUILD/lcmgen/python
# recv_buf_size: room for seconds of every camera's features in each receiver's socket buffer
URL='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'
TAG=F$$_$RANDOM
TMP=$(mktemp -d)
PIDS=()
cleanup() {
  for p in "${PIDS[@]}"; do kill "$p" 2>/dev/null; done
  [ -n "${KEEP:-}" ] || rm -rf "$TMP"
}
trap cleanup EXIT
pass=0; fail=0
ok()  { echo "ok   $1"; pass=$((pass + 1)); }
bad() { echo "FAIL $1"; fail=$((fail + 1)); }
finish() {
  echo "[  PASSED  ] $pass test(s)"
  [ $fail -eq 0 ] || { echo "[  FAILED  ] $fail test(s)"; exit 1; }
  exit 0
}

"$REL/rigpose-render" --out "$TMP/src" --frames 150 --width 320 --height 240 --face-px 256 \
    --ss 1 > "$TMP/render.out" 2>&1 || { cat "$TMP/render.out"; bad "render"; finish; }

# configs NAME LEAD_S: $TMP/NAME_replay.yaml and NAME_lcm.yaml, the rendered run restamped to
# start LEAD_S s from now (daemon/tests/restamp.py: method gc, realtime live).
configs() { "$PY" daemon/tests/restamp.py "$TMP/src" "$TMP" "$1" "$2" "$TAG" ${3:-gc}; }

# rec NAME REGEX: record channels into $TMP/NAME.log until SIGTERM; REC_PID.
rec() {
  rm -f "$TMP/$1.ready"
  "$PY" daemon/tests/lcm_rec.py --url "$URL" --channels "$2" --out "$TMP/$1.log" \
      --ready "$TMP/$1.ready" > "$TMP/$1.rec.out" 2>&1 &
  REC_PID=$!; PIDS+=("$REC_PID")
  for _ in $(seq 100); do [ -e "$TMP/$1.ready" ] && return 0; sleep 0.1; done
  cat "$TMP/$1.rec.out"; return 1
}

# frontend NAME CAM: one front end on the NAME run's replay; FE_PID.
frontend() {
  "$REL/rigpose-frontend" --config "$TMP/$1_replay.yaml" --cameras "$2" --lcm-url "$URL" \
      --quiet >> "$TMP/$1_fe$2.out" 2>&1 &
  FE_PID=$!; PIDS+=("$FE_PID")
}

# ---- A. four front ends + the daemon: the in-process run's poses ------------------------------
configs a 3.0
rec a_poses "POSE_${TAG}_a|STATUS_${TAG}_a" || { bad "recorder did not start"; finish; }
A_REC=$REC_PID
lcm-logger -f --lcm-url="$URL" --channel="FE_${TAG}_CAM.*" "$TMP/feats.lcmlog" \
    > "$TMP/logger.out" 2>&1 &
LOGGER=$!; PIDS+=("$LOGGER")
"$REL/rigpose" --config "$TMP/a_lcm.yaml" --lcm-url "$URL" --quiet --frames 150 \
    --stats-json "$TMP/a_stats.json" > "$TMP/a_daemon.out" 2>&1 &
DPID=$!; PIDS+=("$DPID")
FES=()
for k in 0 1 2 3; do frontend a $k; FES+=("$FE_PID"); done
# The in-process daemon on the same frames, meanwhile (as fast as it goes, into a log file).
"$REL/rigpose" --config "$TMP/a_replay.yaml" --fast --quiet \
    --lcm-url "file://$TMP/inproc.log?mode=w" > "$TMP/inproc.out" 2>&1 || bad "in-process daemon"
timeout 60 tail --pid=$DPID -f /dev/null; wait $DPID; drc=$?
fe_rc=0
for p in "${FES[@]}"; do wait "$p" || fe_rc=$?; done
sleep 0.3
kill -TERM $A_REC; wait $A_REC
kill -INT $LOGGER; wait $LOGGER 2>/dev/null
cat "$TMP/a_daemon.out" | tail -3
[ $drc -eq 0 ] && [ $fe_rc -eq 0 ] && ok "A: daemon (source lcm) and 4 front ends exit 0" \
  || { bad "A: daemon exit $drc, front ends $fe_rc"; cat "$TMP/a_daemon.out" "$TMP"/a_fe*.out; }

# cmp_poses B CHANNEL N [A]: the poses of log B on CHANNEL against the in-process log A
# ($TMP/inproc.log), set by set.
cmp_poses() {
  "$PY" - "${4:-$TMP/inproc.log}" "$1" "$2" "$3" <<'PYEOF'
import sys, lcm
from rigpose import pose_t
a_log, b_log, b_ch, n = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
A = {p.utime: p for p in (pose_t.decode(e.data) for e in lcm.EventLog(a_log, "r")
                          if e.channel.startswith("POSE_"))}
B = [pose_t.decode(e.data) for e in lcm.EventLog(b_log, "r") if e.channel == b_ch]
nums = lambda p: (list(p.position) + list(p.quaternion) + list(p.angles) + list(p.velocity)
                  + list(p.angle_rates) + list(p.covariance))
worst, same, missing = 0.0, 0, 0
for b in B:
    a = A.get(b.utime)
    if a is None:
        missing += 1
        continue
    worst = max(worst, max(abs(x - y) for x, y in zip(nums(a), nums(b))))
    same += (a.flags == b.flags and list(a.features_used) == list(b.features_used)
             and a.n_landmarks == b.n_landmarks)
print("%d poses (in-process %d), %d without an in-process pose, largest difference %.3g, "
      "%d with the same flags / features used / landmarks" % (len(B), len(A), missing, worst, same))
seqs = [p.seq for p in B]
ok = (len(B) == n and len(A) == n and missing == 0 and worst <= 1e-9 and same == n
      and seqs == list(range(n)))
sys.exit(0 if ok else 1)
PYEOF
}
cmp_poses "$TMP/a_poses.log" "POSE_${TAG}_a" 150 \
  && ok "A: 150 poses through the front ends, equal to the in-process run's within 1e-9" \
  || bad "A: poses differ from the in-process run's"
"$PY" -c 'import json, sys; d = json.load(open(sys.argv[1])); print("A: latency frame -> pose '\
'through the front ends: p50 %.3f ms, p99 %.3f ms" % (d["daemon_latency_ms_p50"], '\
'd["daemon_latency_ms_p99"]))' "$TMP/a_stats.json"

# ---- B. the recorded features into the estimator alone -----------------------------------------
# play NAME CONFIG: part A's recording of the features played into a daemon alone on CONFIG,
# its poses recorded into $TMP/NAME_poses.log; drc: the daemon's exit status.
play() {
  rec "$1_poses" "POSE_${TAG}_a" || { bad "recorder did not start"; finish; }
  local prec=$REC_PID
  "$REL/rigpose" --config "$2" --lcm-url "$URL" --quiet --frames 150 \
      > "$TMP/$1_daemon.out" 2>&1 &
  DPID=$!; PIDS+=("$DPID")
  sleep 0.5
  lcm-logplayer --speed=1 --lcm-url="$URL" "$TMP/feats.lcmlog" > "$TMP/$1_player.out" 2>&1
  timeout 10 tail --pid=$DPID -f /dev/null; kill -TERM $DPID 2>/dev/null; wait $DPID; drc=$?
  sleep 0.3
  kill -TERM $prec; wait $prec
}
play b "$TMP/a_lcm.yaml"
[ $drc -eq 0 ] && cmp_poses "$TMP/b_poses.log" "POSE_${TAG}_a" 150 \
  && ok "B: lcm-logger's recording of the features, played into the daemon: the same 150 poses" \
  || { bad "B: the replayed features (daemon exit $drc)"; tail -5 "$TMP/b_daemon.out"; }

# ---- B2. the same recording into a daemon with sets: latest --------------------------------------
# No grouping by time: each of camera 0's 150 messages makes a set at once, at its own time,
# with every other camera's newest message not yet delivered at that camera's own time (the
# same time, or a frame earlier when it came after camera 0's). Every set gives a finite pose at
# the in-process set's time, seq without a gap. Accuracy is not asserted: this render's motion
# is the paper's new random step every frame, which has no meaning between frames, so a camera
# a frame behind is placed by extrapolating on noise (docs/time.md: issue 15's offsets need the
# smooth motion); the largest distance to the in-process poses is printed for the record.
sed 's/^  kind: lcm$/  kind: lcm\n  sets: latest/' "$TMP/a_lcm.yaml" > "$TMP/b2_lcm.yaml"
play b2 "$TMP/b2_lcm.yaml"
"$PY" - "$TMP/inproc.log" "$TMP/b2_poses.log" "POSE_${TAG}_a" <<'PYEOF'
import sys, lcm
from rigpose import pose_t
A = {p.utime: p for p in (pose_t.decode(e.data) for e in lcm.EventLog(sys.argv[1], "r")
                          if e.channel.startswith("POSE_"))}
B = [pose_t.decode(e.data) for e in lcm.EventLog(sys.argv[2], "r") if e.channel == sys.argv[3]]
both = [(A[b.utime], b) for b in B if b.utime in A]
dist = max((sum((x - y) ** 2 for x, y in zip(a.position, b.position)) ** 0.5
            for a, b in both), default=float("inf"))
every = sum(all(n > 0 for n in list(b.features_used)[:4]) for b in B[1:])
finite = all(x == x and abs(x) < 1e30 for b in B for x in list(b.position) + list(b.angles))
print("B2: %d poses (in-process %d), %d at an in-process set's time, seq %s, all finite: %s; "
      "largest position difference %.4f m, %d of %d after the first with every camera's "
      "features used" % (len(B), len(A), len(both), "0.." + str(B[-1].seq) if B else "-",
                         finite, dist, every, max(len(B) - 1, 0)))
ok = (len(B) == 150 and len(both) == 150 and [p.seq for p in B] == list(range(150))
      and finite)
sys.exit(0 if ok else 1)
PYEOF
[ $? -eq 0 ] && [ $drc -eq 0 ] \
  && ok "B2: the recording with sets: latest: a pose per camera-0 frame at its time" \
  || { bad "B2: sets: latest (daemon exit $drc)"; tail -5 "$TMP/b2_daemon.out"; }

# check_flags LOG PAIRS: each camera's messages in LOG count seq 0, 1, ...; FEAT_NEW is set
# exactly on ids not in the camera's previous message; FEAT_MATCHED exactly on ids in the
# partner's message of the same utime (PAIRS "a:b,c:d"; none: never set).
check_flags() {
  "$PY" - "$1" "$2" <<'PYEOF'
import sys, lcm
from rigpose import features_t
log, pairs = sys.argv[1], sys.argv[2]
partner = {}
for p in filter(None, pairs.split(",")):
    a, b = map(int, p.split(":"))
    partner[a], partner[b] = b, a
M = [features_t.decode(e.data) for e in lcm.EventLog(log, "r") if "_CAM" in e.channel]
by = {}
for m in M:
    by.setdefault(m.cam, []).append(m)
at = {(m.cam, m.utime): set(m.id[:m.n]) for m in M}
bad, n_new, n_matched, n_feats = [], 0, 0, 0
for cam, ms in sorted(by.items()):
    if [m.seq for m in ms] != list(range(len(ms))):
        bad.append("camera %d: seq not 0, 1, ..." % cam)
    prev = None
    for m in ms:
        q = at.get((partner.get(cam), m.utime), set())
        for i in range(m.n):
            new = prev is None or m.id[i] not in prev
            matched = m.id[i] in q
            n_new += new; n_matched += matched; n_feats += 1
            if bool(m.flags[i] & features_t.FEAT_NEW) != new or \
               bool(m.flags[i] & features_t.FEAT_MATCHED) != matched:
                bad.append("camera %d seq %d feature %d: flags %d" % (cam, m.seq, i, m.flags[i]))
        prev = set(m.id[:m.n])
print("%d messages from %d cameras, %d features: %d FEAT_NEW, %d FEAT_MATCHED, %d wrong"
      % (len(M), len(by), n_feats, n_new, n_matched, len(bad)), *bad[:3])
sys.exit(0 if not bad and len(M) > 0 and n_new > 0 and (n_matched > 0) == bool(pairs) else 1)
PYEOF
}
check_flags "$TMP/feats.lcmlog" "" \
  && ok "B: the recorded features: seq per camera, FEAT_NEW exact, no FEAT_MATCHED (gc)" \
  || bad "B: the recorded features' seq and flags"

# ---- C. a front end killed and restarted -------------------------------------------------------
configs c 2.0
rec c_poses "POSE_${TAG}_c|STATUS_${TAG}_c" || { bad "recorder did not start"; finish; }
C_REC=$REC_PID
"$REL/rigpose" --config "$TMP/c_lcm.yaml" --lcm-url "$URL" --quiet \
    > "$TMP/c_daemon.out" 2>&1 &
DPID=$!; PIDS+=("$DPID")
FES=()
for k in 0 1 3; do frontend c $k; FES+=("$FE_PID"); done
frontend c 2
sleep 3.5                        # 2 s to the first set, then 1.5 s: about set 45
kill -KILL $FE_PID; wait $FE_PID 2>/dev/null
t_kill=$("$PY" -c 'import time; print(int(time.monotonic() * 1e6))')
sleep 1.5                        # camera 2 silent for longer than timeout_ms (1 s)
frontend c 2                     # restarted: it skips the sets already past and joins
t_back=$("$PY" -c 'import time; print(int(time.monotonic() * 1e6))')
for p in "${FES[@]}"; do wait "$p"; done
wait $FE_PID
sleep 1.5
kill -TERM $DPID; wait $DPID; drc=$?
sleep 0.3
kill -TERM $C_REC; wait $C_REC
grep -E "camera 2|poses published" "$TMP/c_daemon.out"
[ $drc -eq 0 ] && ok "C: daemon exit 0 after SIGTERM" || bad "C: daemon exit $drc"
"$PY" - "$TMP/c_poses.log" "POSE_${TAG}_c" "STATUS_${TAG}_c" "$t_kill" "$t_back" <<'PYEOF'
import math, sys, lcm
from rigpose import pose_t, status_t
log, pch, sch, t_kill, t_back = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
ev = list(lcm.EventLog(log, "r"))
P = [pose_t.decode(e.data) for e in ev if e.channel == pch]
S = [status_t.decode(e.data) for e in ev if e.channel == sch]
fails = []
def check(name, cond):
    print(("ok   " if cond else "FAIL ") + name)
    if not cond:
        fails.append(name)
check("C: %d poses, seq 0..%d without a gap, all finite" % (len(P), len(P) - 1),
      len(P) >= 140 and [p.seq for p in P] == list(range(len(P)))
      and all(math.isfinite(x) for p in P for x in list(p.position) + list(p.covariance)))
GONE = status_t.CAM_GONE
gone = [s for s in S if s.cam_state[2] & GONE]
check("C: the status channel reports camera 2 gone (%d status messages)" % len(gone), len(gone) > 0)
gone_t = gone[0].utime if gone else 0
during = [p for p in P if t_kill < p.utime < t_back]
check("C: poses go on while it is gone: %d poses between the kill and the restart, none using "
      "camera 2" % len(during),
      len(during) >= 30 and all(p.features_used[2] == 0 for p in during[3:])
      and all(sum(p.features_used) > 0 for p in during))
back = [s for s in S if s.utime > gone_t and s.cam_state[2] == status_t.CAM_OK]
check("C: camera 2 ok again on the status channel after the restart", len(back) > 0)
after = [p for p in P if p.utime > t_back]
used = [p.seq for p in after if p.features_used[2] > 0]
first = next((p for p in after if p.features_used[2] > 0), None)
check("C: it rejoins: %d of the %d poses after the restart use camera 2's features, the first "
      "%s ms after the restart (seq %s), and every one of the last 10"
      % (len(used), len(after), "%.0f" % ((first.utime - t_back) / 1e3) if first else "-",
         first.seq if first else None),
      len(after) >= 20 and len(used) >= 10 and all(p.features_used[2] > 0 for p in after[-10:]))
sys.exit(1 if fails else 0)
PYEOF
[ $? -eq 0 ] && ok "C: front end killed, reported, poses go on, rejoins" || bad "C: kill / rejoin"

# ---- D. stereo4: a front end per stereo pair ------------------------------------------------------
configs d 2.5 stereo4
"$REL/rigpose-frontend" --config "$TMP/d_replay.yaml" --cameras 0 --lcm-url memq:// \
    > "$TMP/d_half.out" 2>&1; hrc=$?
[ $hrc -eq 1 ] && grep -q "is in a stereo pair with camera 4 (cam1b)" "$TMP/d_half.out" \
  && ok "D: half a stereo pair refused (exit 1, naming the partner)" \
  || { bad "D: half a pair: exit $hrc"; cat "$TMP/d_half.out"; }
rec d_poses "POSE_${TAG}_d|FE_${TAG}_CAM.*" || { bad "recorder did not start"; finish; }
D_REC=$REC_PID
"$REL/rigpose" --config "$TMP/d_lcm.yaml" --lcm-url "$URL" --quiet --frames 150 \
    > "$TMP/d_daemon.out" 2>&1 &
DPID=$!; PIDS+=("$DPID")
FES=()
frontend d 0,4; FES+=("$FE_PID")
frontend d cam3,cam3b; FES+=("$FE_PID")
"$REL/rigpose" --config "$TMP/d_replay.yaml" --fast --quiet \
    --lcm-url "file://$TMP/d_inproc.log?mode=w" > "$TMP/d_inproc.out" 2>&1 || bad "D: in-process"
timeout 60 tail --pid=$DPID -f /dev/null; wait $DPID; drc=$?
for p in "${FES[@]}"; do wait "$p"; done
sleep 0.3
kill -TERM $D_REC; wait $D_REC
[ $drc -eq 0 ] && cmp_poses "$TMP/d_poses.log" "POSE_${TAG}_d" 150 "$TMP/d_inproc.log" \
  && ok "D: stereo4 through two pair front ends: the in-process run's 150 poses" \
  || { bad "D: stereo4 poses (daemon exit $drc)"; tail -5 "$TMP/d_daemon.out"; }
check_flags "$TMP/d_poses.log" "0:4,2:5" \
  && ok "D: the pairs' features: FEAT_NEW and FEAT_MATCHED exact" \
  || bad "D: the pairs' features' flags"
finish
