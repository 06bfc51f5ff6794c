#!/usr/bin/env bash
# The main job: installs what is missing, builds, and runs the map demo —
# rmap's cuboid map against OctoMap on OctoMap's real scan (../shared/data) or,
# without it, on a simulated building. (rmapd replaces this with the server.)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
scan=../shared/data/octomap/scan.dat.bz2
if [ -f "$scan" ]; then
  source="$scan"
else
  source="sim:building"
fi
mkdir -p out
exec build/bin/rmap-bench map3d --scans "$source" --resolution 0.1 --sim-poses 20 --sim-rings 32 --sim-columns 512 \
  --json out/map3d-demo.json "$@"
