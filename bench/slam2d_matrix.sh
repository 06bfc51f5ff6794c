#!/usr/bin/env bash
# Runs `rmap-bench slam2d` on every CARMEN log of ../shared/data/carmen-2d-raw
# (raw odometry; relations where a file of the same name exists) and
# ../shared/data/carmen-2d (corrected logs: ODOM increments, reference poses
# for ATE/RPE), and on the simulated runs (both 2D laser presets), leaves one
# JSON and one text log per run in out/bench/slam2d/ and prints a markdown
# table for docs/BENCHMARKS.md (also written to out/bench/slam2d/table.md).
# Needs a Release build of rmap-bench and jq. Extra arguments go to every run
# (engine options such as --resolution 0.1; not --odometry, which the runs set).
# Every run with odometry is repeated with --loop-closure on ("-loop-closure"
# rows; LOOP_CLOSURE=0 skips them): its closures are judged against the
# corrected logs of the same run where they exist (--closure-reference; the
# table gives the first one's count of false closures, judged against the
# anchor's pose and against the submap as a whole, and, with two, the count
# both call false), else against the reference poses; where the log has
# relations, also the count they call false (chained from match to query). REPEAT=N runs each corrected
# log with loop closure from N starts (--repeat: the logged one and N − 1 seeded
# rigid moves of the whole run); the last column gives the median ATE over them.
set -euo pipefail
cd "$(dirname "$0")/.."
bench=build/bin/rmap-bench
data=${RMAP_SHARED_DATA_DIR:-../shared/data}
out=out/bench/slam2d
mkdir -p "$out"
[ -x "$bench" ] || { echo "slam2d_matrix: build $bench first (Release)" >&2; exit 1; }
command -v jq >/dev/null || { echo "slam2d_matrix: needs jq" >&2; exit 1; }

runs=()  # names of the JSON files, in table order

run() {  # run NAME ARGS...: one benchmark run, output kept; a failing run is reported, not fatal
  local name=$1
  shift
  echo "== $name" >&2
  if "$bench" slam2d "$@" --json "$out/$name.json" "${extra[@]}" >"$out/$name.txt" 2>&1; then
    runs+=("$name")
  else
    echo "slam2d_matrix: $name failed, see $out/$name.txt" >&2
  fi
}

extra=("$@")
loop_closure=${LOOP_CLOSURE:-1}
repeat=()
[ "${REPEAT:-1}" -gt 1 ] && repeat=(--repeat "$REPEAT")
run_lc() {  # run_lc NAME ARGS...: the same run with loop closure
  local name=$1
  shift
  [ "$loop_closure" = 1 ] && run "$name-loop-closure" "$@" --loop-closure on
  return 0
}
# The corrected logs of each raw log (same scans, found by their ranges): judge the raw runs' closures.
# mit-csail has two corrections, which disagree on one scan's pose by 12° (BENCHMARKS.md §4): both judge.
declare -A corrected_of=([intel]=intel-corrected.log.gz [fr079]=freiburg-079-corrected.log.gz
                         [mit-csail]="csail-corrected.log.gz csail-corrected-subset.robotlaser1.log.gz")
# mit-killian's stamps were rewritten (data README): its relations are placed by counting
# scans 0.44 s apart from scan 20 (how that was found: BENCHMARKS.md §4, *mit-killian's relations*).
declare -A relations_by_count=([mit-killian]="--relations-period 0.44 --relations-first-scan 20")
for log in "$data"/carmen-2d-raw/*.clf*; do
  [ -e "$log" ] || continue
  name=$(basename "$log")
  name=${name%%.clf*}
  args=(--log "$log")
  if [ -f "$data/relations/$name.relations" ]; then
    args+=(--relations "$data/relations/$name.relations" ${relations_by_count[$name]:-})
    run "raw-$name-no-odometry" "${args[@]}" --odometry none  # scan matching alone
  fi
  run "raw-$name" "${args[@]}" --odometry logged  # raw logs: the logged poses are raw odometry
  judge=()
  for corrected in ${corrected_of[$name]:-}; do
    [ -f "$data/carmen-2d/$corrected" ] && judge+=(--closure-reference "$data/carmen-2d/$corrected")
  done
  run_lc "raw-$name" "${args[@]}" --odometry logged "${judge[@]}" --map-image "$out/raw-$name-loop-closure.png" \
    --map-image-max-px 1000
done
# Corrected logs hold scans of these raw logs (same ranges; data README): the raw
# log gives them the stamps the relation files use.
declare -A raw_of=([intel-corrected]=intel.clf.bz2 [freiburg-079-corrected]=fr079.clf.bz2
                   [csail-corrected]=mit-csail.clf.gz [csail-corrected-subset.robotlaser1]=mit-csail.clf.gz)
for log in "$data"/carmen-2d/*.log*; do
  [ -e "$log" ] || continue
  name=$(basename "$log")
  name=${name%%.log*}
  args=(--log "$log")  # auto odometry: ODOM increments, none without ODOM lines
  raw=${raw_of[$name]:-}
  if [ -n "$raw" ] && [ -f "$data/carmen-2d-raw/$raw" ]; then
    args+=(--stamps-from "$data/carmen-2d-raw/$raw")
    relations=$data/relations/${raw%%.*}.relations
    [ -f "$relations" ] && args+=(--relations "$relations")
  fi
  # Where the raw log has two corrections, both judge the closures, the log's own first.
  judge=()
  others=()
  [ -n "$raw" ] && others=(${corrected_of[${raw%%.*}]:-})
  if [ ${#others[@]} -gt 1 ]; then
    judge=(--closure-reference "$log")
    for c in "${others[@]}"; do
      [ "$c" != "$(basename "$log")" ] && [ -f "$data/carmen-2d/$c" ] && judge+=(--closure-reference "$data/carmen-2d/$c")
    done
  fi
  run "corrected-${name/-corrected/}" "${args[@]}"
  run_lc "corrected-${name/-corrected/}" "${args[@]}" "${judge[@]}" "${repeat[@]}"
done
# Raw logs scored against a corrected log of a subset of their scans (same stamps; data README).
for pair in "mit-csail.clf.gz:csail-corrected-subset.robotlaser1.log.gz"; do
  raw=$data/carmen-2d-raw/${pair%%:*}
  reference=$data/carmen-2d/${pair##*:}
  [ -f "$raw" ] && [ -f "$reference" ] || continue
  run "raw-${pair%%.*}-vs-corrected-subset" --log "$raw" --odometry logged --reference "$reference"
  run_lc "raw-${pair%%.*}-vs-corrected-subset" --log "$raw" --odometry logged --reference "$reference"
done
for laser in sick hokuyo; do
  run "sim-building-$laser" --log sim:building --sim-laser "$laser"
  run_lc "sim-building-$laser" --log sim:building --sim-laser "$laser"
done

# One row per run; "–" where a figure does not apply (NaN or absent in the JSON).
{
  echo "| run | scans | odometry | relations used | rel. trans. error m (mean ± std) | rel. rot. error ° (mean ± std) | reference's rel. trans. error m | ATE m | RPE 1 m | ×real time | CPU s | ATE vs truth m | refl. rel. err. | spread raw → calibrated | loop closures (judged, false) | optimisation s | ATE m over starts: median (min–max) |"
  echo "|---|---:|---|---:|---|---|---|---:|---:|---:|---:|---:|---:|---|---|---:|---|"
  for name in "${runs[@]}"; do
    jq -r --arg name "$name" '
      def f(d): if . == null then "–" else (. * pow(10; d) | round / pow(10; d) | tostring) end;
      def pm(x; d): if x.mean == null then "–" else "\(x.mean | f(d)) ± \(x.std | f(d))" end;
      "| \($name) | \(.scans) | \(.odometry) | \(.relations_used) | \(pm(.rel_trans_err_m; 4)) | \(pm(.rel_rot_err_deg; 3)) | \(pm(.reference_rel_trans_err_m; 4)) | \(.ate_vs_reference_m | f(3)) | \(.rpe_1m_m | f(4)) | \(.realtime_factor | f(0)) | \(.cpu_s | f(2)) | \(.ate_vs_truth_m | f(4)) | \(.reflectivity_rel_err_median | f(3)) | \(if .reflectivity_spread_raw == null then "–" else "\(.reflectivity_spread_raw | f(3)) → \(.reflectivity_spread_calibrated | f(3))" end) | \(if .loop_closure == null then "–" else "\(.loop_closure.closures) (\(.loop_closure.closures_judged), \(.loop_closure.false_closures // "–")\(if .loop_closure.false_against_submap == null then "" else "; against the submap \(.loop_closure.false_against_submap)" end)\(if .loop_closure.false_by_all_judges == null then "" else "; by every judge \(.loop_closure.false_by_all_judges)" end)\(if .loop_closure.false_by_relations == null then "" else "; by the relations \(.loop_closure.false_by_relations) of \(.loop_closure.closures_judged_by_relations)" end))" end) | \(.loop_closure.optimization_s | f(2)) | \(if .repeated == null then "–" else "\(.repeated.ate_m_median | f(3)) (\(.repeated.ate_m_min | f(3))–\(.repeated.ate_m_max | f(3))), \(.repeated.runs | length) starts" end) |"
    ' "$out/$name.json"
  done
} | tee "$out/table.md"
