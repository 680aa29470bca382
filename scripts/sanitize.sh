#!/usr/bin/env bash
# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer (issue 8), in a build
# of its own (build-asan/, clang, -O1). Any finding fails: UBSan halts on the first error, ASan
# always does, LeakSanitizer reports leaks at exit. Third-party leaks that are not ours to fix are
# listed, with the reason, in tests/sanitizers/lsan.supp.
#   scripts/sanitize.sh            install what is missing, build, run the whole suite under them
# Environment: S2C_BUILD_DIR (default build-asan), S2C_SANITIZE_CC / S2C_SANITIZE_CXX (default
# clang / clang++: it builds this project in half the time GCC takes with the sanitizers, 14 vs
# 28 min on 2 cores), CTEST_ARGS (more ctest arguments, e.g. "-L unit").
#
# Timings on 2 cores are in bench/README.md ("Sanitizer job"); CI runs this after the normal suite.
set -euo pipefail
cd "$(dirname "$0")/.."
here="$PWD"
export S2C_BUILD_DIR="${S2C_BUILD_DIR:-build-asan}"
# The benchmarks' CGAL/OpenVDB comparisons take long to build and no test runs them.
export S2C_CMAKE_ARGS="-DS2C_SANITIZE=ON -DS2C_BENCH_PEERS=OFF ${S2C_CMAKE_ARGS:-}"
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=0:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:${UBSAN_OPTIONS:-}"
export LSAN_OPTIONS="suppressions=$here/tests/sanitizers/lsan.supp:print_suppressions=0:${LSAN_OPTIONS:-}"
scripts/install-deps.sh --fuzz   # clang and its sanitizer runtimes
CC="${S2C_SANITIZE_CC:-clang}" CXX="${S2C_SANITIZE_CXX:-clang++}" \
  cmake -S . -B "$S2C_BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release $S2C_CMAKE_ARGS
cmake --build "$S2C_BUILD_DIR" -j "$(nproc)"
# Sanitized executables are several times slower: a longer per-test timeout than the normal suite's
# (the e2e tests' own timeouts are scaled in tests/e2e/CMakeLists.txt).
ctest --test-dir "$S2C_BUILD_DIR" --output-on-failure -j 2 --timeout 3600 ${CTEST_ARGS:-}
