#!/usr/bin/env bash
# summary.sh LOG... - prints the logs tests/run_one.sh wrote, in the order given, then the
# failed and skipped tests (with the reason each skipped test printed) and one line
# "tests: N passed, N failed, N skipped". Exit 1 when a test failed or none passed.
set -u
pass=0; fail=0; skip=0; failed=(); skipped=()
for log in "$@"; do
  if [ ! -f "$log" ]; then fail=$((fail + 1)); failed+=("$log (no log)"); continue; fi
  sed '$d' "$log"
  last=$(tail -1 "$log")
  name=$(head -1 "$log"); name=${name#== }
  rc=$(sed -E 's/.*rc=([0-9]+).*/\1/' <<<"$last")
  p=$(sed -E 's/.*passed=([0-9]+).*/\1/' <<<"$last")
  f=$(sed -E 's/.*failed=([0-9]+).*/\1/' <<<"$last")
  s=$(sed -E 's/.*skipped=([0-9]+).*/\1/' <<<"$last")
  secs=$(sed -E 's/.*seconds=([0-9.]+).*/\1/' <<<"$last")
  pass=$((pass + p)); fail=$((fail + f)); skip=$((skip + s))
  [ "$f" -gt 0 ] && failed+=("$name (exit $rc)")
  if [ "$s" -gt 0 ]; then
    why=$(grep -m1 -E '^\[  SKIPPED \] [0-9]+ test\(s\): ' "$log" | sed -E 's/^\[  SKIPPED \] [0-9]+ test\(s\): *//')
    skipped+=("$name: $s skipped${why:+ ($why)}")
  fi
  echo "-- $name: $p passed, $f failed, $s skipped, ${secs} s"
done
echo
for x in "${skipped[@]+"${skipped[@]}"}"; do echo "SKIPPED: $x"; done
for x in "${failed[@]+"${failed[@]}"}"; do echo "FAILED: $x"; done
echo "tests: $pass passed, $fail failed, $skip skipped"
[ $fail -eq 0 ] && [ $pass -gt 0 ]
