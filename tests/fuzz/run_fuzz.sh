#!/usr/bin/env bash
# run_fuzz.sh FUZZ_DIR SECONDS TARGET... - make fuzz: each libFuzzer target FUZZ_DIR/fuzz_<t> for
# SECONDS, one after the other, on its growing corpus FUZZ_DIR/corpus/<t> plus its seeds
# (tests/fuzz/seed/<t>, FUZZ_DIR/gen/<t>) and regression inputs (tests/fuzz/regress/<t>), with the
# dictionary tests/fuzz/<t>.dict when there is one. Inputs up to 64 KiB; an input running longer
# than 25 s is a hang (as in run_corpus.sh: a real hang never ends, and a loaded machine can stall
# a process for seconds). A crash, sanitizer report, leak, out-of-memory or hang is copied into
# tests/fuzz/regress/<t>/ (make test then runs it until the bug is fixed; a bug in code this
# project may not change goes to tests/fuzz/found/<t>/ instead, by hand). Prints one line per
# target (executions, corpus size, coverage, findings) and exits 1 if anything was found.
# libFuzzer's slow-unit-* files are not findings: it writes one for any input that finished but
# took longer than -report_slow_units (a stall of the machine is enough); they are listed, kept in
# the artifacts folder and not copied.
set -u
dir=$1; secs=$2; shift 2
root=$(cd "$(dirname "$0")/../.." && pwd)
found=0
printf '%-22s %12s %10s %8s %8s %s\n' target executions exec/s corpus cov findings
for t in "$@"; do
  bin=$dir/fuzz_$t
  corpus=$dir/corpus/$t; art=$dir/artifacts/$t; log=$dir/logs/$t.log
  mkdir -p "$corpus" "$art" "$(dirname "$log")"
  rm -f "$art"/*
  extra=()
  for d in "$root/tests/fuzz/seed/$t" "$dir/gen/$t" "$root/tests/fuzz/regress/$t"; do
    [ -d "$d" ] && extra+=("$d")
  done
  dict=()
  [ -f "$root/tests/fuzz/$t.dict" ] && dict=(-dict="$root/tests/fuzz/$t.dict")
  "$bin" "$corpus" "${extra[@]}" "${dict[@]}" -max_total_time="$secs" -timeout=25 -report_slow_units=10 \
      -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 -artifact_prefix="$art/" \
      > "$log" 2>&1
  rc=$?
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  last=$(grep -E '^#[0-9]+' "$log" | tail -1)
  corp=$(sed -n 's/.* corp: \([0-9]*\)\/.*/\1/p' <<<"$last")
  cov=$(sed -n 's/.* cov: \([0-9]*\) .*/\1/p' <<<"$last")
  arts=()
  slow=()
  for a in "$art"/*; do
    [ -e "$a" ] || continue
    case $(basename "$a") in slow-unit-*) slow+=("$a") ;; *) arts+=("$a") ;; esac
  done
  what=none
  [ ${#slow[@]} -gt 0 ] && what="none (slow unit, not a finding: $(grep -m1 '^Slowest unit' "$log"))"
  if [ $rc -ne 0 ] || [ ${#arts[@]} -gt 0 ]; then
    found=1
    mkdir -p "$root/tests/fuzz/regress/$t"
    for a in "${arts[@]}"; do cp "$a" "$root/tests/fuzz/regress/$t/"; done
    what="FOUND (exit $rc): $(grep -m1 -E 'SUMMARY|ERROR: libFuzzer' "$log" | cut -c1-100); log $log"
  fi
  printf '%-22s %12s %10s %8s %8s %s\n' "$t" "${execs:-?}" "${rate:-?}" "${corp:-?}" "${cov:-?}" "$what"
done
if [ $found -ne 0 ]; then
  echo "fuzz: findings copied to tests/fuzz/regress/<target>/ (see the logs above)"
  exit 1
fi
echo "fuzz: $# targets, ${secs} s each: no crash, no sanitizer report, no leak, no hang"
