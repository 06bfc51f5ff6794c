#!/usr/bin/env bash
# The unit and integration tests again, built with AddressSanitizer + UndefinedBehaviorSanitizer
# (RMAP_SANITIZE) into build-sanitize/: every rmapd, rmap, rmap-sim and rmap-bench the end-to-end
# tests start is the sanitized build too. Any finding (memory error, leak at exit, undefined
# behaviour) aborts that process, so its test fails. Browser, Python and Docker tests run only in
# scripts/test.sh: they exercise the same binaries through slower clients.
# Needs what scripts/setup.sh installs.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build-sanitize -DCMAKE_BUILD_TYPE=Release -DRMAP_SANITIZE=ON -DRMAP_BUILD_TESTS=ON \
  -DRMAP_BUILD_BENCH=ON "$@"
cmake --build build-sanitize -j"$(nproc)"
# abort_on_error: a finding ends the process with SIGABRT whatever its own exit path;
# the processes the tests start inherit these.
export ASAN_OPTIONS=abort_on_error=1:detect_leaks=1:detect_stack_use_after_return=0:strict_init_order=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
ctest --test-dir build-sanitize --output-on-failure -j"$(nproc)" -E '^(browser_|python_client_|docker_files)'
