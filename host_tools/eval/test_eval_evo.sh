#!/usr/bin/env bash
# test_eval_evo.sh - rigpose-eval against the field's tool (make test): trajectories of the
# rigpose daemon, recorded as LCM logs of rigpose.pose_t, are read by rigpose-eval, exported
# to TUM, and evo_ape / evo_rpe (PyPI evo in .venv) evaluate the same TUM files. The ATE
# (no alignment, SE(3), Sim(3)) RMSE and max and the RPE translation RMSE must agree to 1e-6 m.
# Runs, all deterministic and offline:
#   sim-stereo4, sim-gc: the daemon on the simulated rig (config/sim.yaml), 100 sets each;
#   render-stereo4: a 12-set rendered replay folder (rigpose-render) through the daemon's image
#                   pipeline, truth from truth.csv.
# Also: the KITTI and EuRoC exports are read back by evo_traj, and the EuRoC truth export
# (--format euroc) is the reference of evo_ape euroc, whose ATE statistics equal evo_ape tum's on
# the TUM export to 1e-9 m.
set -u
eval_bin=${RP_EVAL_BIN:-build/release/rigpose-eval}
daemon=${RP_DAEMON_BIN:-build/release/rigpose}
render=$(dirname "$eval_bin")/rigpose-render
work=${RP_EVAL_WORK:-build/eval/work}/evo
PY=${PY:-.venv/bin/python}
EVO=$(dirname "$PY")
rm -rf "$work" && mkdir -p "$work"
pass=0; fail=0
check() { if eval "$2"; then echo "[       OK ] $1"; pass=$((pass+1)); else echo "[  FAILED  ] $1"; fail=$((fail+1)); fi; }

# --- the runs --------------------------------------------------------------------------------
sed -e 's/^  method: stereo4.*/  method: gc/' -e 's/^  pairs: .*/  cams: [cam1, cam2, cam3, cam4]/' \
    config/sim.yaml > "$work/sim_gc.yaml"
"$daemon" --config config/sim.yaml --frames 100 --fast --quiet \
    --lcm-url "file://$work/sim-stereo4.log?mode=w" > "$work/daemon.out" 2>&1
check "daemon: sim stereo4 log" '[ -s "$work/sim-stereo4.log" ]'
"$daemon" --config "$work/sim_gc.yaml" --frames 100 --fast --quiet \
    --lcm-url "file://$work/sim-gc.log?mode=w" >> "$work/daemon.out" 2>&1
check "daemon: sim gc log" '[ -s "$work/sim-gc.log" ]'
runs="sim-stereo4 sim-gc"
if [ -x "$render" ]; then
  "$render" --out "$work/render" --frames 12 --width 320 --height 240 --face-px 256 --ss 1 \
      > "$work/render.out" 2>&1
  "$daemon" --config "$work/render/rig.yaml" --fast --quiet \
      --lcm-url "file://$work/render-stereo4.log?mode=w" >> "$work/daemon.out" 2>&1
  check "daemon: rendered replay stereo4 log" '[ -s "$work/render-stereo4.log" ]'
  runs="$runs render-stereo4"
else
  echo "[  FAILED  ] $render not built"; fail=$((fail+1))
fi

# --- rigpose-eval and evo on the same TUM files ------------------------------------------------
for run in $runs; do
  truth=()
  [ "$run" = render-stereo4 ] && truth=(--truth "$work/render/truth.csv")
  for align in none se3 sim3; do
    "$eval_bin" "${truth[@]}" --est "$run=$work/$run.log" --align $align --tum-dir "$work/tum" \
        --kitti-dir "$work/kitti" --json "$work/$run-$align.json" > "$work/$run-$align.out" 2>&1
    check "rigpose-eval $run ($align)" '[ $? -eq 0 ]' || cat "$work/$run-$align.out"
    flag=""; [ $align = se3 ] && flag="-a"; [ $align = sim3 ] && flag="-as"
    "$EVO/evo_ape" tum "$work/tum/truth.tum" "$work/tum/$run.tum" $flag --no_warnings \
        --save_results "$work/ape-$run-$align.zip" > /dev/null 2>&1
    "$EVO/evo_rpe" tum "$work/tum/truth.tum" "$work/tum/$run.tum" --delta 1 --delta_unit f \
        --no_warnings --save_results "$work/rpe-$run-$align.zip" > /dev/null 2>&1
    res=$("$PY" - "$work/$run-$align.json" "$work/ape-$run-$align.zip" "$work/rpe-$run-$align.zip" "$run" <<'PYEOF'
import json, sys, zipfile
ours = json.load(open(sys.argv[1]))
ape = json.load(zipfile.ZipFile(sys.argv[2]).open("stats.json"))
rpe = json.load(zipfile.ZipFile(sys.argv[3]).open("stats.json"))
n = sys.argv[4]
pairs = [("ATE rmse", ours["eval_%s_ate_rmse_m" % n], ape["rmse"]),
         ("ATE max", ours["eval_%s_ate_max_m" % n], ape["max"]),
         ("RPE rmse", ours["eval_%s_rpe_trans_rmse_m" % n], rpe["rmse"])]
worst = max(abs(a - b) for _, a, b in pairs)
print(" ".join("%s %.9f/%.9f" % p for p in pairs), "worst_diff %.3g" % worst,
      "OK" if worst < 1e-6 else "BAD")
PYEOF
)
    echo "  $run $align (rigpose-eval/evo): $res"
    check "$run $align: rigpose-eval and evo agree to 1e-6 m" '[[ "$res" == *" OK" ]]'
    # The EuRoC export (--format euroc) read by evo_ape euroc, which takes EuRoC's ground-truth
    # CSV as the reference and a TUM estimate: the same result as evo_ape tum on the TUM pair.
    "$eval_bin" "${truth[@]}" --est "$run=$work/$run.log" --format euroc \
        --out-dir "$work/euroc" > /dev/null 2>&1
    "$EVO/evo_ape" euroc "$work/euroc/truth.csv" "$work/tum/$run.tum" $flag --no_warnings \
        --save_results "$work/ape-euroc-$run-$align.zip" > /dev/null 2>&1
    res=$("$PY" - "$work/ape-$run-$align.zip" "$work/ape-euroc-$run-$align.zip" <<'PYEOF'
import json, sys, zipfile
tum = json.load(zipfile.ZipFile(sys.argv[1]).open("stats.json"))
eur = json.load(zipfile.ZipFile(sys.argv[2]).open("stats.json"))
worst = max(abs(tum[k] - eur[k]) for k in ("rmse", "mean", "median", "max", "min"))
print("TUM rmse %.12f EuRoC rmse %.12f worst_diff %.3g" % (tum["rmse"], eur["rmse"], worst),
      "OK" if worst < 1e-9 else "BAD")
PYEOF
)
    echo "  $run $align (evo_ape tum / euroc): $res"
    check "$run $align: evo_ape euroc on --format euroc equals evo_ape tum" '[[ "$res" == *" OK" ]]'
  done
done

# --- KITTI and EuRoC exports read by evo ------------------------------------------------------
"$EVO/evo_traj" euroc "$work/euroc/sim-gc.csv" --no_warnings > "$work/traj-euroc.out" 2>&1
check "evo_traj reads the EuRoC export (100 poses)" 'grep -q "100 poses" "$work/traj-euroc.out"'
"$EVO/evo_traj" kitti "$work/kitti/sim-gc.kitti" --no_warnings > "$work/traj.out" 2>&1
check "evo_traj reads the KITTI export (100 poses)" 'grep -q "100 poses" "$work/traj.out"'

if [ $fail -eq 0 ]; then echo "[  PASSED  ] $pass test(s)."; else echo "[  FAILED  ] $fail test(s)."; exit 1; fi
