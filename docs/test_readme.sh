#!/usr/bin/env bash
# test_readme.sh BUILD - README.md's subscribers do what README says (make test; under the
# multicast lock, SERIAL_TESTS): its C, C++ and Python blocks are cut out of README.md as they
# stand, built as their first comment line says (C and C++ with -Wall -Wextra -Werror, ASan +
# UBSan; Python from the wheel installed with pip), started, and each must print every pose of
# a 60-set daemon run, seq 0..59. LCM_DEFAULT_URL puts them and the daemon on port 7669 of
# rigpose's group with ttl=0: this host only, apart from anyone's `make run`.
set -u
BUILD=${1:?usage: test_readme.sh BUILD}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
cd "$ROOT"
PY=${PY:-.venv/bin/python}
GEN=$BUILD/lcmgen
SAN="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
export LCM_DEFAULT_URL='udpm://239.255.76.67:7669?ttl=0'
TMP=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null; rm -rf "$TMP"' EXIT
pass=0; fail=0
ok()  { echo "[       OK ] $1"; pass=$((pass + 1)); }
bad() { echo "[  FAILED  ] $1"; fail=$((fail + 1)); }

# The first fenced block of each language in README.md.
for lang in c cpp python; do
  awk -v l="$lang" '$0 == "```" l {on = 1; next} on && $0 == "```" {exit} on {print}' README.md \
      > "$TMP/sub.$lang"
  [ -s "$TMP/sub.$lang" ] || bad "README.md has no \`\`\`$lang block"
done
head -1 "$TMP/sub.c" | grep -q 'cc sub.c' || bad "README's C block does not start with its build line"

${CC:-gcc} -Wall -Wextra -Werror $SAN "$TMP/sub.c" -I"$GEN/c" "$GEN/librigpose_lcm.a" -llcm \
    -o "$TMP/sub_c" 2>"$TMP/cc.err" && ok "README's C subscriber builds (-Wall -Wextra -Werror)" \
  || { cat "$TMP/cc.err"; bad "README's C subscriber does not build"; }
# -fno-sanitize=vptr: Debian's LCM 1.3.1 header (lcm-cpp-impl.hpp:88, the member-function
# subscription) fails UBSan's vptr check at -O0; that is LCM's code, not README's.
${CXX:-g++} -Wall -Wextra -Werror $SAN -fno-sanitize=vptr "$TMP/sub.cpp" -I"$GEN/cpp" -llcm -o "$TMP/sub_cpp" \
    2>"$TMP/cxx.err" && ok "README's C++ subscriber builds (-Wall -Wextra -Werror)" \
  || { cat "$TMP/cxx.err"; bad "README's C++ subscriber does not build"; }
"$PY" -m pip install -q --disable-pip-version-check --no-deps --no-index --target "$TMP/site" \
    "$GEN"/rigpose_lcm-*-py3-none-any.whl > "$TMP/pip.out" 2>&1 \
  || { cat "$TMP/pip.out"; bad "the wheel does not install"; }

# stdbuf (line-buffered stdout, as on a terminal) preloads a library before ASan's runtime.
export ASAN_OPTIONS=verify_asan_link_order=0
[ -x "$TMP/sub_c" ] && stdbuf -oL "$TMP/sub_c" > "$TMP/out_c" 2>&1 &
[ -x "$TMP/sub_cpp" ] && stdbuf -oL "$TMP/sub_cpp" > "$TMP/out_cpp" 2>&1 &
env -u PYTHONPATH PYTHONPATH="$TMP/site" PYTHONUNBUFFERED=1 "$PY" "$TMP/sub.python" \
    > "$TMP/out_python" 2>&1 &
sleep 2   # the subscribers subscribe (README's code has no ready signal)
"$BUILD/release/rigpose" --config config/sim.yaml --frames 60 --quiet \
    --lcm-url "$LCM_DEFAULT_URL" > "$TMP/daemon.out" 2>&1 || bad "daemon: $(cat "$TMP/daemon.out")"
sleep 0.5
kill $(jobs -p) 2>/dev/null; wait 2>/dev/null
for lang in c cpp python; do
  got=$(grep -Ec '^seq [0-9]+ t -?[0-9.]+ -?[0-9.]+ -?[0-9.]+ m$' "$TMP/out_$lang" 2>/dev/null)
  seqs=$(awk '/^seq /{print $2}' "$TMP/out_$lang" 2>/dev/null | tr '\n' ' ')
  if [ "$seqs" = "$(seq -s ' ' 0 59) " ]; then
    ok "README's $lang subscriber printed all 60 poses in order ($(sed -n 60p "$TMP/out_$lang"))"
  else
    head -5 "$TMP/out_$lang"; bad "README's $lang subscriber: $got pose lines"
  fi
done

echo
echo "[  PASSED  ] $pass test(s)."
[ $fail -eq 0 ] && exit 0
echo "[  FAILED  ] $fail test(s)."
exit 1
