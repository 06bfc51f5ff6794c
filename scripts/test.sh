#!/usr/bin/env bash
# The test command: installs what is missing, builds everything and runs every test.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh -DRMAP_BUILD_TESTS=ON -DRMAP_BUILD_BENCH=ON
ctest --test-dir build --output-on-failure -j"$(nproc)"
