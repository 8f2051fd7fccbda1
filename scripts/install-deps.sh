#!/usr/bin/env bash
# Installs what rigpose needs to build, test and benchmark, from Debian's packages (and PyPI for
# Python-side tools). Idempotent: checks each package first and only calls apt-get for the
# missing ones, so a second run costs a few dpkg queries. The Java side (liblcm-java, a JDK, a
# JRE with AWT and jchart2d for lcm-spy) builds the jar of the LCM types; Xvfb, ImageMagick,
# x11-utils, xdotool take lcm-spy's screenshot (scripts/lcm-spy-screenshot.sh).
#
# usage: scripts/install-deps.sh [host|cross|py|all]   (default: all)
#   host   Debian packages for the host build, tests, tools, the V4L2 VM test and the fuzz
#          targets (clang with its libFuzzer runtime, libclang-rt-14-dev: Debian 12's clang 14)
#   cross  the aarch64 toolchain, qemu-user and arm64 libraries (Debian multiarch)
#   py     host + a virtual environment .venv/ (Debian's python3) with the PyPI packages of
#          the Python-side clients and tests (lcm bindings, evo; foxglove-sdk for rigpose-view,
#          mcap, mcap-protobuf-support and websockets to check its output)
set -euo pipefail

want=${1:-all}

host_pkgs=(build-essential g++ make pkg-config
           libeigen3-dev libcmocka-dev liblcm-dev liblcm-bin
           libopencv-dev libopengv-dev libceres-dev libyaml-dev valgrind
           python3 python3-venv opencv-doc
           qemu-system-x86 busybox-static xz-utils cpio libpng-dev libjpeg-dev
           liblcm-java libjchart2d-java default-jdk-headless default-jre xvfb imagemagick
           x11-utils xdotool clang libclang-rt-14-dev)
cross_pkgs=(gcc-aarch64-linux-gnu g++-aarch64-linux-gnu qemu-user libcmocka-dev:arm64)

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

missing=()
is_installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q 'install ok installed'; }

pkgs=()
py_pkgs=(lcm evo numpy foxglove-sdk mcap mcap-protobuf-support websockets)
py_imports="import lcm, evo, numpy, foxglove, mcap, mcap_protobuf, websockets"
VENV=${RIGPOSE_VENV:-$(cd "$(dirname "$0")/.." && pwd)/.venv}

case "$want" in
  py)    pkgs=("${host_pkgs[@]}") ;;
  host)  pkgs=("${host_pkgs[@]}") ;;
  cross) pkgs=("${cross_pkgs[@]}") ;;
  all)   pkgs=("${host_pkgs[@]}" "${cross_pkgs[@]}") ;;
  *) echo "install-deps: unknown set '$want' (host|cross|py|all)" >&2; exit 2 ;;
esac

install_py() {
  # Debian's interpreter (not whatever python3 comes first on PATH), PyPI packages in .venv/.
  if [ -x "$VENV/bin/python" ] && "$VENV/bin/python" -c "$py_imports" 2>/dev/null; then return 0; fi
  echo "install-deps: PyPI ${py_pkgs[*]} into $VENV"
  [ -x "$VENV/bin/python" ] || /usr/bin/python3 -m venv "$VENV"
  "$VENV/bin/python" -m pip install -q --disable-pip-version-check "${py_pkgs[@]}"
  "$VENV/bin/python" -c "$py_imports"
}

for p in "${pkgs[@]}"; do is_installed "$p" || missing+=("$p"); done
if [ ${#missing[@]} -eq 0 ]; then
  if [ "$want" = py ] || [ "$want" = all ]; then install_py; fi
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
need_arm64=0
for p in "${missing[@]}"; do case "$p" in *:arm64) need_arm64=1 ;; esac; done
if [ $need_arm64 -eq 1 ] && ! dpkg --print-foreign-architectures | grep -qx arm64; then
  $SUDO dpkg --add-architecture arm64
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
if [ "$want" = py ] || [ "$want" = all ]; then install_py; fi
