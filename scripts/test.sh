#!/usr/bin/env bash
# The test command: installs what is missing, builds everything with AddressSanitizer +
# UndefinedBehaviorSanitizer (RMAP_SANITIZE, into build-sanitize/) and runs every test there:
# unit, end-to-end against real (sanitized) rmapd, rmap, rmap-sim and rmap-bench processes,
# browser, Python client and Docker files. Any memory error, leak or undefined behaviour aborts
# the process that has it, so its test fails. Then it fuzzes every entry point of tests/fuzz
# briefly (RMAP_FUZZ_SECONDS per target, default 15; 0 skips it).
# RMAP_TEST_BUILD=release runs the same tests on the Release build in build/ instead (quicker
# to rebuild while working; the benchmarks and scripts/run.sh use that build).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
if [ "${RMAP_TEST_BUILD:-sanitize}" = release ]; then
  build=build
  bash scripts/configure.sh "$build" -DRMAP_BUILD_TESTS=ON -DRMAP_BUILD_BENCH=ON
else
  build=build-sanitize
  bash scripts/configure.sh "$build" -DRMAP_SANITIZE=ON -DRMAP_BUILD_TESTS=ON -DRMAP_BUILD_BENCH=ON
  # abort_on_error: a finding ends the process with SIGABRT whatever its own exit path; the
  # processes the tests start inherit these.
  export ASAN_OPTIONS=abort_on_error=1:detect_leaks=1:detect_stack_use_after_return=0:strict_init_order=1
  export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
fi
cmake --build "$build" -j"$(nproc)"
ctest --test-dir "$build" --output-on-failure -j"$(nproc)"
fuzz_seconds=${RMAP_FUZZ_SECONDS:-15}
if ((fuzz_seconds > 0)); then bash scripts/fuzz.sh "$fuzz_seconds"; fi
