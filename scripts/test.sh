#!/usr/bin/env bash
# The test command: installs what is missing, builds everything and runs every test, then
# fuzzes every entry point of tests/fuzz briefly (RMAP_FUZZ_SECONDS per target, default 15;
# 0 skips it). The tests under AddressSanitizer + UBSan: scripts/test-sanitized.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh -DRMAP_BUILD_TESTS=ON -DRMAP_BUILD_BENCH=ON
ctest --test-dir build --output-on-failure -j"$(nproc)"
fuzz_seconds=${RMAP_FUZZ_SECONDS:-15}
if ((fuzz_seconds > 0)); then bash scripts/fuzz.sh "$fuzz_seconds"; fi
