#!/usr/bin/env bash
# Installs what rigpose needs to build, test and benchmark, from Debian's packages (and PyPI for
# Python-side tools). Idempotent: checks each package first and only calls apt-get for the
# missing ones, so a second run costs a few dpkg queries.
#
# usage: scripts/install-deps.sh [host|cross|all]   (default: all)
set -euo pipefail

want=${1:-all}

host_pkgs=(build-essential g++ make pkg-config
           libeigen3-dev libcmocka-dev liblcm-dev liblcm-bin
           libopencv-dev libopengv-dev libyaml-dev valgrind)
cross_pkgs=(gcc-aarch64-linux-gnu g++-aarch64-linux-gnu qemu-user libcmocka-dev:arm64)

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

missing=()
is_installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q 'install ok installed'; }

pkgs=()
case "$want" in
  host)  pkgs=("${host_pkgs[@]}") ;;
  cross) pkgs=("${cross_pkgs[@]}") ;;
  all)   pkgs=("${host_pkgs[@]}" "${cross_pkgs[@]}") ;;
  *) echo "install-deps: unknown set '$want' (host|cross|all)" >&2; exit 2 ;;
esac

for p in "${pkgs[@]}"; do is_installed "$p" || missing+=("$p"); done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "install-deps: installing ${missing[*]}"
need_arm64=0
for p in "${missing[@]}"; do case "$p" in *:arm64) need_arm64=1 ;; esac; done
if [ $need_arm64 -eq 1 ] && ! dpkg --print-foreign-architectures | grep -qx arm64; then
  $SUDO dpkg --add-architecture arm64
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
