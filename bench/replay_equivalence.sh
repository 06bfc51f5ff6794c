#!/usr/bin/env bash
# Replays the shared intel-corrected CARMEN log and OctoMap's scan.dat through `rmap replay`
# into a fresh rmapd and checks that the server holds the maps the benchmarks build offline
# (`rmap-bench replay-check`: 3D cell states, counts and a grid of occupancy answers; 2D the
# map_server export byte for byte and the trajectory). Twice: live, and after a restart that
# loads the maps from rmapd's snapshots (where blocks are stored fused, as rmap-bench map3d
# counts them). Last, `rmap-bench map3d` itself for its cuboid count. About a minute.
# Usage: bench/replay_equivalence.sh [shared-data-dir]   (Release build in build/)
set -euo pipefail
cd "$(dirname "$0")/.."
data=${1:-../shared/data}
bin=build/bin
scans=$data/octomap/scan.dat.bz2
log=$data/carmen-2d/intel-corrected.log.gz
for f in "$scans" "$log" "$bin/rmapd" "$bin/rmap" "$bin/rmap-bench"; do
  [[ -e $f ]] || { echo "missing $f" >&2; exit 2; }
done
work=$(mktemp -d)
out=out/replay-equivalence
mkdir -p "$out"
pid=
stop_rmapd() { if [[ -n $pid ]]; then kill -TERM "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true; pid=; fi; }
trap 'stop_rmapd; rm -rf "$work"' EXIT

start_rmapd() {
  "$bin/rmapd" --listen 127.0.0.1:0 --data-dir "$work/data" >"$work/rmapd.out" 2>>"$work/rmapd.err" &
  pid=$!
  for _ in $(seq 200); do
    port=$(sed -n 's#^rmapd listening on http://127.0.0.1:\([0-9]*\)/.*#\1#p' "$work/rmapd.out")
    [[ -n $port ]] && return 0
    sleep 0.1
  done
  echo "rmapd did not start:" >&2; cat "$work/rmapd.err" >&2; exit 1
}

check() {  # $1: live | restored
  "$bin/rmap-bench" replay-check --server "http://127.0.0.1:$port" --map scan --scans "$scans" --resolution 0.05 \
    --json "$out/scan-$1.json"
  "$bin/rmap-bench" replay-check --server "http://127.0.0.1:$port" --map intel --log "$log" \
    --robot intel-corrected --json "$out/intel-$1.json"
}

start_rmapd
echo "rmapd on port $port"
"$bin/rmap" replay --quiet --server "ws://127.0.0.1:$port" --map scan --resolution 0.05 --json "$out/replay-scan.json" "$scans"
"$bin/rmap" replay --quiet --server "ws://127.0.0.1:$port" --map intel --json "$out/replay-intel.json" "$log"
sleep 1  # trajectory poses are written every 0.5 s
status=0
echo "--- live"
check live || status=1
stop_rmapd
start_rmapd
echo "--- restored from the snapshots (port $port)"
check restored || status=1
stop_rmapd
echo "--- rmap-bench map3d (beam model, the figures of docs/BENCHMARKS.md)"
"$bin/rmap-bench" map3d --scans "$scans" --resolution 0.05 --sensor-model beam --json "$out/map3d-scan.json" >/dev/null
bench_cuboids=$(jq '.rmap.cuboids' "$out/map3d-scan.json")
restored_cuboids=$(jq '.map3d.server.cuboids' "$out/scan-restored.json")
echo "rmap-bench map3d: $bench_cuboids cuboids; the restored server: $restored_cuboids"
[[ $bench_cuboids == "$restored_cuboids" ]] || status=1
echo "results in $out/"
[[ $status == 0 ]] && echo "EQUAL" || echo "DIFFERENT"
exit $status
