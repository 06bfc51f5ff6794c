#!/usr/bin/env bash
# The main job: installs what is missing, builds, starts rmapd with its
# embedded defaults (SQLite store in ./rmap-data, loopback only) plus a feed
# of simulated robots, and prints the URL to open. Ctrl-C stops both.
#   RMAP_LISTEN=127.0.0.1:8080  RMAP_DATA_DIR=rmap-data  RMAP_SIM_ROBOTS=2
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
listen=${RMAP_LISTEN:-127.0.0.1:8080}
data_dir=${RMAP_DATA_DIR:-rmap-data}
robots=${RMAP_SIM_ROBOTS:-2}

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
echo "streaming $robots simulated robots into map 'sim' (Ctrl-C stops)"
# Robots drive their tour again and again until stopped.
while kill -0 "${pids[0]}" 2>/dev/null; do
  build/bin/rmap-sim --server "$ws" --robots "$robots" --duration 600 --rate 5 || sleep 1
done
