#!/usr/bin/env bash
# run_corpus.sh FUZZ_BIN - one libFuzzer target (build/fuzz/fuzz_<t>) run once over every input of
# its committed seeds (tests/fuzz/seed/<t>/), its regression inputs (tests/fuzz/regress/<t>/: what
# fuzzing once crashed) and the seeds made at build time (build/fuzz/gen/<t>/): a plain test for
# make test. Prints cmocka-style lines; exit 1 if any input crashes or trips a sanitizer.
set -u
bin=$1
t=$(basename "$bin"); t=${t#fuzz_}
root=$(cd "$(dirname "$0")/../.." && pwd)
dirs=("$root/tests/fuzz/seed/$t" "$root/tests/fuzz/regress/$t" "$(dirname "$bin")/gen/$t")
files=()
for d in "${dirs[@]}"; do
  [ -d "$d" ] && while IFS= read -r f; do files+=("$f"); done < <(find "$d" -type f | sort)
done
n_regress=$(find "$root/tests/fuzz/regress/$t" -type f 2>/dev/null | wc -l)
if [ ${#files[@]} -eq 0 ]; then
  echo "[  FAILED  ] 1 test(s): fuzz_$t: no seed input"
  exit 1
fi
out=$("$bin" -timeout=25 -rss_limit_mb=2048 "${files[@]}" 2>&1); rc=$?
if [ $rc -eq 0 ]; then
  echo "[       OK ] fuzz_$t: ${#files[@]} inputs ($n_regress regression) run, no crash, no sanitizer report"
  echo "[  PASSED  ] 1 test(s)."
else
  echo "$out" | grep -E "Running:|ERROR|SUMMARY|runtime error" | tail -20
  echo "[  FAILED  ] 1 test(s): fuzz_$t crashed on an input (exit $rc)"
  exit 1
fi
