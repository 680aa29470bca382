#!/usr/bin/env bash
# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer (issue 8), in a build
# of its own (build-asan/, -O1). Any finding fails: UBSan halts on the first error, ASan always
# does, LeakSanitizer reports leaks at exit. Third-party leaks that are not ours to fix are listed,
# with the reason, in tests/sanitizers/lsan.supp.
#   scripts/sanitize.sh            install what is missing, build, run the whole suite under them
#   scripts/sanitize.sh --ci       the same without the four longest tests (CI's budget: see below)
# Environment: S2C_BUILD_DIR (default build-asan), CTEST_ARGS (more ctest arguments, e.g. "-L unit").
#
# Timings on 2 cores (bench/README.md has the record): the build ~25 min, the whole suite ~40 min
# (crash_safety, repair_real, real_data and the defect-variant test re-run whole pipelines dozens
# of times and take 3-15 min each under ASan); --ci runs everything else in ~12 min, so that CI
# (normal suite + fuzzing + this) stays within its 90 minutes.
set -euo pipefail
cd "$(dirname "$0")/.."
here="$PWD"
export S2C_BUILD_DIR="${S2C_BUILD_DIR:-build-asan}"
# The benchmarks' CGAL/OpenVDB comparisons take long to build and no test runs them.
export S2C_CMAKE_ARGS="-DS2C_SANITIZE=ON -DS2C_BENCH_PEERS=OFF ${S2C_CMAKE_ARGS:-}"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=0:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:${UBSAN_OPTIONS:-}"
export LSAN_OPTIONS="suppressions=$here/tests/sanitizers/lsan.supp:print_suppressions=0:${LSAN_OPTIONS:-}"
scripts/install-deps.sh
cmake -S . -B "$S2C_BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release $S2C_CMAKE_ARGS
cmake --build "$S2C_BUILD_DIR" -j "$(nproc)"
# Sanitized executables are 2-5× slower: a longer per-test timeout than the normal suite's.
select=()
if [[ "${1:-}" == --ci ]]; then
  select=(-E '^(e2e\.crash_safety|e2e\.repair_real|e2e\.real_data|MakeDefects\.PlateVariantsHoldTheirDefects)$')
fi
ctest --test-dir "$S2C_BUILD_DIR" --output-on-failure -j 2 --timeout 3600 "${select[@]}" ${CTEST_ARGS:-}
