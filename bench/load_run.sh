#!/usr/bin/env bash
# The recorded load run (docs/RELIABILITY.md "Load", BENCHMARKS.md §9): a fresh rmapd with a
# 1 GiB memory bound and 256 KiB viewer send queues, then `rmap-bench load` against it, then
# rmapd's CPU time and peak resident memory from the kernel. Extra arguments go to
# rmap-bench load (defaults: 64 robots, 8 of them 2D-laser, 2 messages/s each, 32 viewers of
# which 8 stalled, 4 query connections, 30 s).
# Usage: bench/load_run.sh [rmap-bench load options]   (Release build in build/)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=build/bin
for f in "$bin/rmapd" "$bin/rmap-bench"; do
  [[ -x $f ]] || { echo "missing $f" >&2; exit 2; }
done
work=$(mktemp -d)
out=out/load
mkdir -p "$out"
pid=
stop_rmapd() { if [[ -n $pid ]]; then kill -TERM "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true; pid=; fi; }
trap 'stop_rmapd; rm -rf "$work"' EXIT

cat >"$work/rmapd.yaml" <<YAML
limits:
  max_memory_bytes: 1073741824
  viewer_send_queue_bytes: 262144
YAML
"$bin/rmapd" --listen 127.0.0.1:0 --data-dir "$work/data" --config "$work/rmapd.yaml" \
  >"$work/rmapd.out" 2>"$work/rmapd.err" &
pid=$!
port=
for _ in $(seq 200); do
  port=$(sed -n 's#^rmapd listening on http://127.0.0.1:\([0-9]*\)/.*#\1#p' "$work/rmapd.out")
  [[ -n $port ]] && break
  sleep 0.1
done
[[ -n $port ]] || { echo "rmapd did not start:" >&2; cat "$work/rmapd.err" >&2; exit 1; }

status=0
"$bin/rmap-bench" load --server "http://127.0.0.1:$port" --json "$out/load.json" "$@" || status=$?
# utime + stime in clock ticks (fields 14, 15 of /proc/PID/stat), and the kernel's peak RSS.
read -r utime stime < <(awk '{print $14, $15}' "/proc/$pid/stat")
echo "rmapd CPU $(( (utime + stime) / $(getconf CLK_TCK) )) s, $(grep VmHWM "/proc/$pid/status")"
echo "rmapd warnings/errors: $(grep -c -E '\[(warning|error|critical)\]' "$work/rmapd.err" || true)"
exit $status
