#!/usr/bin/env bash
# Configures a build directory: Release, Ninja when the directory is new (it keeps building the
# next target's sources while the previous one links; an existing directory keeps its generator).
# Usage: scripts/configure.sh DIR [CMAKE_ARGS...]
set -euo pipefail
cd "$(dirname "$0")/.."
dir=$1
shift
generator=()
if [ ! -f "$dir/CMakeCache.txt" ] && command -v ninja >/dev/null; then generator=(-G Ninja); fi
cmake -S . -B "$dir" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release "$@"
