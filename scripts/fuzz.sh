#!/usr/bin/env bash
# Builds the libFuzzer targets of tests/fuzz (clang, ASan + UBSan) in build-fuzz and runs
# each for SECONDS_PER_TARGET (default 60) on a copy of its seed corpus
# (tests/fuzz/corpus/<target>), with its dictionary when there is one; RMAP_FUZZ_PARALLEL
# targets at a time (default: one per core; each fuzzer runs on one core).
# Exits 1 when a target crashes, leaks, hangs (-timeout) or runs out of memory
# (-rss_limit_mb), printing the reproducer's path: rerun it with
#   build-fuzz/bin/<target>_fuzz <reproducer>
# Usage: scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]   (targets: robot_message, ...)
# Environment: RMAP_FUZZ_BUILD_DIR (build-fuzz), RMAP_FUZZ_JOBS (2, build jobs), RMAP_FUZZ_PARALLEL (nproc),
#   RMAP_FUZZ_TIMEOUT (10 s per input), RMAP_FUZZ_RSS_MB (2048).
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=${1:-60}
(($# > 0)) && shift
build=${RMAP_FUZZ_BUILD_DIR:-build-fuzz}
timeout_s=${RMAP_FUZZ_TIMEOUT:-10}
rss_mb=${RMAP_FUZZ_RSS_MB:-2048}

targets=("$@")
if ((${#targets[@]} == 0)); then
  for source in tests/fuzz/*_fuzz.cc; do
    name=$(basename "$source" .cc)
    targets+=("${name%_fuzz}")
  done
fi

launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
start=$SECONDS
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DRMAP_BUILD_FUZZ=ON -DRMAP_BUILD_TESTS=OFF -DRMAP_BUILD_BENCH=OFF "${launcher[@]}" >/dev/null
cmake --build "$build" -j"${RMAP_FUZZ_JOBS:-2}" --target "${targets[@]/%/_fuzz}"
echo "fuzz: built ${#targets[@]} targets in $((SECONDS - start)) s"

# Runs one target; prints its one-line result (and where to look when it failed).
fuzz_target() {
  local target=$1 run="$build/fuzz-runs/$1" started=$SECONDS dict=() candidate executions reproducer
  rm -rf "$run"
  mkdir -p "$run/corpus" "$run/artifacts"
  cp tests/fuzz/corpus/"$target"/* "$run/corpus/"
  # octomap_bt and octomap_ot share octomap.dict.
  for candidate in "tests/fuzz/$target.dict" "tests/fuzz/${target%_*}.dict"; do
    if [ -f "$candidate" ]; then
      dict=(-dict="$candidate")
      break
    fi
  done
  if "$build/bin/${target}_fuzz" "$run/corpus" "${dict[@]}" -max_total_time="$seconds" -timeout="$timeout_s" \
    -rss_limit_mb="$rss_mb" -artifact_prefix="$run/artifacts/" -print_final_stats=1 >"$run/log" 2>&1; then
    executions=$(sed -n 's/^stat::number_of_executed_units: *//p' "$run/log")
    echo "fuzz: $target ok: $executions inputs in $((SECONDS - started)) s, corpus $(ls "$run/corpus" | wc -l) files"
    return 0
  fi
  echo "fuzz: $target FAILED after $((SECONDS - started)) s (log: $run/log)"
  grep -E '^(==[0-9]+==ERROR|SUMMARY|.*runtime error)' "$run/log" | head -5 || true
  for reproducer in "$run"/artifacts/*; do
    [ -e "$reproducer" ] && echo "fuzz: reproducer $reproducer; rerun: $build/bin/${target}_fuzz $reproducer"
  done
  return 1
}

parallel=${RMAP_FUZZ_PARALLEL:-$(nproc)}
failed=0
running=0
for target in "${targets[@]}"; do
  if ((running >= parallel)); then
    wait -n || failed=1
    running=$((running - 1))
  fi
  fuzz_target "$target" &
  running=$((running + 1))
done
while ((running > 0)); do
  wait -n || failed=1
  running=$((running - 1))
done
echo "fuzz: total $((SECONDS - start)) s"
exit "$failed"
