#!/usr/bin/env bash
# Runs `rmap-bench map3d` over the datasets, resolutions and thread counts of
# docs/BENCHMARKS.md and leaves one JSON per run in out/bench/ (Release build).
set -euo pipefail
cd "$(dirname "$0")/.."
bench=build/bin/rmap-bench
data=../shared/data
mkdir -p out/bench
sources=("$data/octomap/scan.dat.bz2:scan" "$data/3d-scans/3dtk-example:3dtk" "sim:geb079:geb079")
for entry in "${sources[@]}"; do
  source=${entry%:*}
  name=${entry##*:}
  for res in 0.05 0.1; do
    "$bench" map3d --scans "$source" --resolution "$res" --threads 1 --sensor-model both \
      --json "out/bench/$name-$res-t1.json" | tee "out/bench/$name-$res-t1.txt"
    "$bench" map3d --scans "$source" --resolution "$res" --threads 2 --sensor-model beam \
      --json "out/bench/$name-$res-t2.json" | tee "out/bench/$name-$res-t2.txt"
  done
done
