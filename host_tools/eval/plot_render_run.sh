#!/usr/bin/env bash
# plot_render_run.sh BUILD OUT.png [FRAMES] [WxH] - the README's plot: one rendered run
# (rigpose-render, seed 1, run 0) replayed through the rigpose daemon once per method (stereo4,
# stereo2, gc, rc, cam1), each recorded as an LCM log, then rigpose-eval: ATE / RPE table and
# the six-panel PNG against truth.csv. Several minutes (rendering dominates).
#   host_tools/eval/plot_render_run.sh build docs/rigpose_eval_render.png 100 320x240
set -eu
BUILD=${1:?usage: plot_render_run.sh BUILD OUT.png [FRAMES] [WxH]}
png=${2:?usage: plot_render_run.sh BUILD OUT.png [FRAMES] [WxH]}
frames=${3:-100}
size=${4:-320x240}
bin=$BUILD/release
work=$BUILD/eval/render_run
rm -rf "$work" && mkdir -p "$work"
"$bin/rigpose-render" --out "$work/replay" --frames "$frames" --width "${size%x*}" \
    --height "${size#*x}" --face-px 512
rig=$work/replay/rig.yaml
logs=()
for m in stereo4 stereo2 gc rc cam1; do
  case $m in
    stereo4) est='  method: stereo4\n  pairs: [[cam1, cam1b], [cam3, cam3b]]\n' ;;
    stereo2) est='  method: stereo2\n  pairs: [[cam1, cam1b]]\n' ;;
    gc|rc)   est="  method: $m\n  cams: [cam1, cam2, cam3, cam4]\n" ;;
    *)       est="  method: $m\n" ;;
  esac
  # the same rig file beside frames.csv, with this method's estimator section
  sed '/^estimator:/,$d' "$rig" > "$work/replay/rig_$m.yaml"
  printf 'estimator:\n%b  sigma_px: 0.5\n' "$est" >> "$work/replay/rig_$m.yaml"
  "$bin/rigpose" --config "$work/replay/rig_$m.yaml" --fast --quiet \
      --lcm-url "file://$(cd "$work" && pwd)/$m.log?mode=w" | tail -1
  logs+=("$work/$m.log")
done
"$bin/rigpose-eval" --truth "$work/replay/truth.csv" "${logs[@]}" --plot "$png" \
    --title "rigpose-render (seed 1, run 0, $size, $frames sets) replayed through the rigpose daemon: estimates vs ground truth"
