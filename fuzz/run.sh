#!/usr/bin/env bash
# Builds the libFuzzer targets with clang + ASan + UBSan (in build-fuzz/) and runs each for
# SECONDS (default 60), one per core at a time, starting from its seed corpus. A crash, sanitizer
# report, leak or hang (> 10 s per input) is saved to fuzz/crashes/TARGET/ and makes the script
# fail; turn it into a regression by fixing the bug and moving the file to fuzz/regressions/TARGET/.
#   fuzz/run.sh [SECONDS]            all targets
#   TARGETS="mesh pcd" fuzz/run.sh 30
# Results (executions, corpus size, crashes per target) go to build-fuzz/fuzz-results.md.
set -uo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
targets="${TARGETS:-mesh pcd stream features_json edit_script usb_profile}"
build="${S2C_FUZZ_BUILD:-build-fuzz}"

scripts/install-deps.sh --fuzz || exit 1
CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DS2C_FUZZ=ON > "$build.cmake.log" 2>&1 \
  || { cat "$build.cmake.log"; exit 1; }
cmake --build "$build" --target fuzz_all -j "$(nproc)" || exit 1

results="$build/fuzz-results.md"
echo "| target | seconds | executions | exec/s | corpus | crashes |" > "$results"
echo "|---|---|---|---|---|---|" >> "$results"

# One target for SECONDS; its exit code goes to $build/fuzz-$t.rc.
fuzz_one() {
  local t="$1" corpus="$build/corpus/$1" crashes="fuzz/crashes/$1" log="$build/fuzz-$1.log"
  mkdir -p "$corpus" "$crashes"
  cp -n fuzz/corpus/"$t"/* "$corpus"/ 2>/dev/null || true
  # Leaks are reported by the regression test's sanitizer run, not here: libFuzzer's leak check
  # trips on the process-wide caches of OpenCV and TBB.
  S2C_FUZZ_PLATE="$PWD/fixtures/parts/plate.stl" "$build/bin/fuzz_$t" "$corpus" -max_total_time="$seconds" \
    -timeout=10 -rss_limit_mb=4096 -detect_leaks=0 -artifact_prefix="$crashes/" -print_final_stats=1 > "$log" 2>&1
  echo $? > "$build/fuzz-$t.rc"
}

# A fuzzer is single-threaded: run as many at once as there are cores, each still for SECONDS.
jobs_max=$(nproc)
for t in $targets; do
  while (($(jobs -rp | wc -l) >= jobs_max)); do wait -n; done
  fuzz_one "$t" &
done
wait

failed=0
for t in $targets; do
  corpus="$build/corpus/$t"; crashes="fuzz/crashes/$t"; log="$build/fuzz-$t.log"
  rc=$(cat "$build/fuzz-$t.rc" 2>/dev/null || echo 1)
  execs=$(grep -o 'stat::number_of_executed_units: [0-9]*' "$log" | awk '{print $2}')
  rate=$(grep -o 'stat::average_exec_per_sec: *[0-9]*' "$log" | awk '{print $2}')
  n=$(ls "$corpus" | wc -l)
  found=$(ls "$crashes" 2>/dev/null | wc -l)
  echo "| $t | $seconds | ${execs:-?} | ${rate:-?} | $n | $found |" >> "$results"
  if [[ $rc != 0 || $found != 0 ]]; then
    failed=1
    echo "fuzz_$t: FAILED (exit $rc); see $log and $crashes/" >&2
    grep -m5 -E "ERROR|SUMMARY|deadly|Assertion" "$log" >&2
  fi
done
cat "$results"
exit $failed
