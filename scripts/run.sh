#!/usr/bin/env bash
# The main job: installs what is missing, builds, starts rmapd with its
# embedded defaults (SQLite store in ./rmap-data, loopback only) plus a feed
# of simulated robots (lidar robots for the 3D map, 2D-laser robots tracked by
# the 2D reflectivity SLAM), and prints the URL to open. Ctrl-C stops both.
#   RMAP_LISTEN=127.0.0.1:8080  RMAP_DATA_DIR=rmap-data  RMAP_SIM_ROBOTS=2  RMAP_SIM_LASER2D_ROBOTS=1
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
listen=${RMAP_LISTEN:-127.0.0.1:8080}
data_dir=${RMAP_DATA_DIR:-rmap-data}
robots=${RMAP_SIM_ROBOTS:-2}
laser2d_robots=${RMAP_SIM_LASER2D_ROBOTS:-1}

pids=()
cleanup() { kill "${pids[@]}" 2>/dev/null || true; wait 2>/dev/null || true; }
trap cleanup EXIT INT TERM

out=$(mktemp)
build/bin/rmapd --listen "$listen" --data-dir "$data_dir" "$@" >"$out" &
pids+=($!)
for _ in $(seq 1 300); do
  grep -q "listening on" "$out" && break
  kill -0 "${pids[0]}" 2>/dev/null || { echo "rmapd did not start" >&2; exit 1; }
  sleep 0.1
done
url=$(grep -o 'http://[^ ]*' "$out" | head -1)
rm -f "$out"
ws=${url/http:/ws:}
ws=${ws%/}
echo "rmapd is serving on $url  — open it in a browser; maps: ${url}v1/maps"
echo "streaming $robots lidar robots and $laser2d_robots 2D-laser robots into map 'sim' (Ctrl-C stops)"
if [ "$laser2d_robots" -gt 0 ]; then
  echo "2D SLAM layers: tick '2D layers' in the viewer (occupancy or reflectivity), or"
  echo "  ${url}v1/maps/sim/layers  ${url}v1/maps/sim/layers/reflectivity/8/{x}/{y}.png  ${url}v1/maps/sim/grid2d.pgm"
  echo "  rmap-sim prints the 2D robots' pose error against the truth once a second"
fi
# Robots drive their tour again and again until stopped (2D-laser robots
# resume where the server's log left them, so their odometry stays continuous).
while kill -0 "${pids[0]}" 2>/dev/null; do
  build/bin/rmap-sim --server "$ws" --robots "$robots" --laser2d-robots "$laser2d_robots" --duration 600 --rate 5 ||
    sleep 1
done
