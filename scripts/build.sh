#!/usr/bin/env bash
# Configures and builds rmap (Release) into build/; binaries land in build/bin/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/configure.sh build "$@"
cmake --build build -j"$(nproc)"
