#!/usr/bin/env bash
# run_one.sh TEST LOG - runs one test program or script (programs through $RP_TEST_RUNNER when
# set, e.g. qemu-aarch64) and writes its output to LOG, framed for tests/summary.sh: a first
# line "== TEST" and a last line "rp-test: rc=N passed=N failed=N skipped=N seconds=S".
# Counts come from cmocka's summary lines; a test that exits 0 without any counts is one
# passed test, one that exits non-zero without a FAILED count one failed test. A test that
# runs longer than $RP_TEST_TIMEOUT seconds (default 1800) is killed and counted as failed.
set -u
t=$1; log=$2
mkdir -p "$(dirname "$log")"
runner=${RP_TEST_RUNNER:-}
start=$(date +%s.%N)
if [ -n "$runner" ] && [ "$(head -c 4 "$t" 2>/dev/null | od -An -c | tr -d ' ')" = "177ELF" ]; then
  out=$(timeout "${RP_TEST_TIMEOUT:-1800}" $runner "$t" 2>&1); rc=$?
else
  out=$(timeout "${RP_TEST_TIMEOUT:-1800}" "$t" 2>&1); rc=$?
fi
end=$(date +%s.%N)
count() { grep -Eo "^\[  $1 *\] [0-9]+" <<<"$out" | grep -Eo '[0-9]+$' | awk '{s += $1} END {print s + 0}'; }
n_ok=$(count PASSED); n_bad=$(count FAILED); n_skip=$(count SKIPPED)
if [ $rc -ne 0 ] && [ "$n_bad" -eq 0 ]; then n_bad=1; fi
if [ $rc -eq 0 ] && [ "$n_ok" -eq 0 ] && [ "$n_skip" -eq 0 ]; then n_ok=1; fi
[ $rc -eq 124 ] && out="$out"$'\n'"run_one: killed after ${RP_TEST_TIMEOUT:-1800} s"
{
  echo "== $t"
  echo "$out"
  printf 'rp-test: rc=%d passed=%d failed=%d skipped=%d seconds=%.1f\n' "$rc" "$n_ok" "$n_bad" \
      "$n_skip" "$(awk -v a="$start" -v b="$end" 'BEGIN {print b - a}')"
} > "$log"
