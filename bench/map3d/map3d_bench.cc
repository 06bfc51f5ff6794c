#include "map3d/map3d_bench.h"

#include "common/machine.h"

#include <chrono>
#include <ctime>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <thread>

#include "map3d/cuboid_map.h"
#include "map3d/octomap_side.h"
#include "map3d/scan_update.h"

namespace rmap::bench {
namespace {

using map3d::CellKey;
using map3d::CellState;
using Clock = std::chrono::steady_clock;
using json = nlohmann::json;

double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// CPU seconds of the whole process (every thread), user and system. On a
/// machine shared with other jobs it counts only the time this process ran,
/// which wall time does not.
double processCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

CellState stateOf(const map3d::OccupancyParams& p, float log_odds) {
  return log_odds >= p.occupied_threshold_log_odds ? CellState::kOccupied : CellState::kFree;
}

/// Training and held-out scans of OctoMap's cross-validation protocol: every
/// 5th scan is held out; a dataset of fewer than 5 scans holds out every 5th
/// point of each scan instead.
struct CrossValidationSplit {
  std::vector<datasets::PointScan> training, held_out;
  std::string protocol;
};

CrossValidationSplit splitForCrossValidation(const std::vector<datasets::PointScan>& scans) {
  CrossValidationSplit split;
  if (scans.size() >= 5) {
    split.protocol = "every 5th scan held out";
    for (size_t i = 0; i < scans.size(); ++i) (i % 5 == 4 ? split.held_out : split.training).push_back(scans[i]);
    return split;
  }
  split.protocol = "every 5th point of each scan held out (fewer than 5 scans)";
  for (const datasets::PointScan& s : scans) {
    datasets::PointScan train{s.sensor_origin_m, {}}, held{s.sensor_origin_m, {}};
    for (size_t i = 0; i < s.points_m.size(); ++i) (i % 5 == 4 ? held : train).points_m.push_back(s.points_m[i]);
    split.training.push_back(std::move(train));
    split.held_out.push_back(std::move(held));
  }
  return split;
}

struct RmapRun {
  std::unique_ptr<map3d::CuboidMap> map;
  double insert_s = 0.0;
  double insert_cpu_s = 0.0;
};

RmapRun runRmap(const std::vector<datasets::PointScan>& scans, double resolution_m,
                const map3d::OccupancyParams& occupancy, const map3d::FusionParams& fusion, int threads) {
  RmapRun run;
  run.map = std::make_unique<map3d::CuboidMap>(resolution_m, occupancy, fusion);
  const map3d::InsertOptions options{threads, map3d::InvalidPoints::kSkip};
  const auto t0 = Clock::now();
  const double cpu0 = processCpuSeconds();
  for (const datasets::PointScan& s : scans) {
    if (!s.points_m.empty()) run.map->insertScan(s.sensor_origin_m, s.points_m, options);
  }
  run.map->fuseAll(threads);  // counted: the stored map is the fused one
  run.insert_s = secondsSince(t0);
  run.insert_cpu_s = processCpuSeconds() - cpu0;
  return run;
}

struct OctomapRun {
  std::unique_ptr<OctomapSide> tree;
  double insert_s = 0.0;
  double insert_cpu_s = 0.0;
};

OctomapRun runOctomap(const std::vector<datasets::PointScan>& scans, double resolution_m,
                      const map3d::OccupancyParams& occupancy, int threads) {
  OctomapRun run;
  run.tree = std::make_unique<OctomapSide>(resolution_m, occupancy, threads);
  run.tree->prepare(scans);
  const auto t0 = Clock::now();
  const double cpu0 = processCpuSeconds();
  for (size_t i = 0; i < scans.size(); ++i) {
    if (!scans[i].points_m.empty()) run.tree->insert(i);
  }
  run.tree->finish();
  run.insert_s = secondsSince(t0);
  run.insert_cpu_s = processCpuSeconds() - cpu0;
  return run;
}

/// Share of cells known to either map whose states agree (unknown in one and
/// known in the other counts as disagreement).
double agreement(const map3d::CuboidMap& rmap, const OctomapSide& octomap) {
  uint64_t rmap_known = 0, both_known = 0, same = 0;
  const map3d::OccupancyParams& p = rmap.occupancyParams();
  rmap.forEachKnownCell([&](const CellKey& c, float log_odds) {
    ++rmap_known;
    const CellState o = octomap.state(c);
    if (o == CellState::kUnknown) return;
    ++both_known;
    same += o == stateOf(p, log_odds);
  });
  const uint64_t either = rmap_known + octomap.knownCells() - both_known;
  return either ? static_cast<double>(same) / static_cast<double>(either) : 1.0;
}

/// Point queries per second of both maps over the same cells: every known
/// cell of rmap's map (up to 500,000, evenly sampled) and as many random cells
/// of its bounding box, so hits and misses both count.
json queryRates(const map3d::CuboidMap& rmap, const OctomapSide& octomap) {
  std::vector<CellKey> cells;
  const uint64_t known = rmap.stats().known_cells;
  const uint64_t stride = std::max<uint64_t>(1, known / 500000);
  uint64_t n = 0;
  rmap.forEachKnownCell([&](const CellKey& c, float) {
    if (n++ % stride == 0) cells.push_back(c);
  });
  CellKey lo, hi;
  if (cells.empty() || !rmap.bounds(lo, hi)) return nullptr;
  std::mt19937 rng(7);
  const size_t hits = cells.size();
  for (size_t i = 0; i < hits; ++i) {
    CellKey c;
    for (int a = 0; a < 3; ++a) c[a] = std::uniform_int_distribution<int32_t>(lo[a], hi[a])(rng);
    cells.push_back(c);
  }
  uint64_t occupied = 0;
  auto t0 = Clock::now();
  for (const CellKey& c : cells) occupied += rmap.queryCell(c).state == CellState::kOccupied;
  const double rmap_s = secondsSince(t0);
  uint64_t occupied_octomap = 0;
  t0 = Clock::now();
  for (const CellKey& c : cells) occupied_octomap += octomap.state(c) == CellState::kOccupied;
  const double octomap_s = secondsSince(t0);
  return {{"queries", cells.size()},
          {"rmap_per_s", cells.size() / rmap_s},
          {"octomap_per_s", cells.size() / octomap_s},
          {"ratio", octomap_s / rmap_s},
          {"occupied_answers", {{"rmap", occupied}, {"octomap", occupied_octomap}}}};
}

/// OctoMap's cross-validation score: share of the held-out scans' endpoint
/// cells found occupied and ray cells found free, per scan semantics.
template <class StateFn>
double crossValidationAccuracy(const std::vector<datasets::PointScan>& held_out, const map3d::Grid& grid,
                               const map3d::OccupancyParams& params, StateFn&& state_of) {
  uint64_t total = 0, correct = 0;
  map3d::OccupancyParams exact = params;  // the protocol's cells are OctoMap's
  exact.free_space_tracing = map3d::FreeSpaceTracing::kOctomapExact;
  for (const datasets::PointScan& s : held_out) {
    if (s.points_m.empty()) continue;
    map3d::ScanUpdate update;
    update.gather(grid, exact, s.sensor_origin_m, s.points_m);
    update.resolve();
    for (const map3d::BlockMarks& m : update.blocks()) {
      m.occupied.forEach([&](int i) {
        ++total;
        correct += state_of(map3d::cellOf(m.key, i)) == CellState::kOccupied;
      });
      m.free.forEach([&](int i) {
        ++total;
        correct += state_of(map3d::cellOf(m.key, i)) == CellState::kFree;
      });
    }
  }
  return total ? static_cast<double>(correct) / static_cast<double>(total) : 0.0;
}

/// Share of known cells whose state equals the world's at the cell centre.
template <class ForEach>
double truthAccuracy(const sim::VoxelWorld& world, const map3d::Grid& grid, ForEach&& for_each_known) {
  uint64_t total = 0, correct = 0;
  for_each_known([&](const CellKey& c, CellState s) {
    ++total;
    const bool truly_occupied = world.occupied(grid.center(c));
    correct += truly_occupied == (s == CellState::kOccupied);
  });
  return total ? static_cast<double>(correct) / static_cast<double>(total) : 0.0;
}

json compareOnce(const BenchDataset& data, const Map3dBenchOptions& o, const map3d::OccupancyParams& occupancy,
                 const map3d::FusionParams& fusion, uint64_t points) {
  json out;
  std::cerr << "  rmap insert ..." << std::endl;
  RmapRun rmap = runRmap(data.scans, o.resolution_m, occupancy, fusion, o.threads);
  std::cerr << "  octomap insert ..." << std::endl;
  OctomapRun octo = runOctomap(data.scans, o.resolution_m, occupancy, o.threads);
  const map3d::MapStats stats = rmap.map->stats();
  out["rmap"] = {{"insert_s", rmap.insert_s},
                 {"insert_cpu_s", rmap.insert_cpu_s},
                 {"points_per_s", points / rmap.insert_s},
                 {"memory_bytes", stats.memory_bytes},
                 {"cuboids", stats.cuboids},
                 {"blocks", stats.blocks},
                 {"known_cells", stats.known_cells}};
  out["octomap"] = {{"insert_s", octo.insert_s},
                    {"insert_cpu_s", octo.insert_cpu_s},
                    {"points_per_s", points / octo.insert_s},
                    {"memory_bytes", octo.tree->memoryBytes()},
                    {"leaves", octo.tree->leaves()},
                    {"known_cells", octo.tree->knownCells()}};
  out["speedup"] = octo.insert_s / rmap.insert_s;
  out["speedup_cpu"] = octo.insert_cpu_s / rmap.insert_cpu_s;
  out["memory_ratio"] = static_cast<double>(stats.memory_bytes) / static_cast<double>(octo.tree->memoryBytes());
  out["cuboid_ratio"] = static_cast<double>(stats.cuboids) / static_cast<double>(octo.tree->leaves());
  out["point_query"] = queryRates(*rmap.map, *octo.tree);
  std::cerr << "  agreement ..." << std::endl;
  out["agreement"] = agreement(*rmap.map, *octo.tree);
  {
    // fusion off: tolerance 0 and OctoMap's own ray walks, which must equal OctoMap cell for cell
    map3d::FusionParams no_fusion = fusion;
    no_fusion.tolerance_log_odds = 0.0f;
    map3d::OccupancyParams exact = occupancy;
    exact.free_space_tracing = map3d::FreeSpaceTracing::kOctomapExact;
    RmapRun off = runRmap(data.scans, o.resolution_m, exact, no_fusion, o.threads);
    out["fusion_off"] = {{"insert_s", off.insert_s},
                         {"speedup", octo.insert_s / off.insert_s},
                         {"speedup_cpu", octo.insert_cpu_s / off.insert_cpu_s},
                         {"cuboids", off.map->stats().cuboids},
                         {"memory_bytes", off.map->stats().memory_bytes},
                         {"agreement", agreement(*off.map, *octo.tree)}};
  }

  std::cerr << "  cross-validation ..." << std::endl;
  const CrossValidationSplit split = splitForCrossValidation(data.scans);
  RmapRun rmap_train = runRmap(split.training, o.resolution_m, occupancy, fusion, o.threads);
  OctomapRun octo_train = runOctomap(split.training, o.resolution_m, occupancy, o.threads);
  const map3d::Grid& grid = rmap.map->grid();
  out["cv_protocol"] = split.protocol;
  out["cv_accuracy"] = {
      {"rmap", crossValidationAccuracy(split.held_out, grid, occupancy,
                                       [&](const CellKey& c) { return rmap_train.map->queryCell(c).state; })},
      {"octomap", crossValidationAccuracy(split.held_out, grid, occupancy,
                                          [&](const CellKey& c) { return octo_train.tree->state(c); })}};

  if (data.truth) {
    std::cerr << "  truth accuracy ..." << std::endl;
    out["truth_accuracy"] = {
        {"rmap", truthAccuracy(*data.truth, grid,
                               [&](auto&& fn) {
                                 rmap.map->forEachKnownCell(
                                     [&](const CellKey& c, float v) { fn(c, stateOf(occupancy, v)); });
                               })},
        {"octomap", truthAccuracy(*data.truth, grid, [&](auto&& fn) { octo.tree->forEachKnownCell(fn); })}};
  } else {
    out["truth_accuracy"] = nullptr;
  }
  return out;
}

void printRow(const std::string& model, const json& r) {
  std::cout << model << ": rmap " << r["rmap"]["insert_s"].get<double>() << " s, " << r["rmap"]["cuboids"]
            << " cuboids, " << r["rmap"]["memory_bytes"] << " B | octomap " << r["octomap"]["insert_s"].get<double>()
            << " s, " << r["octomap"]["leaves"] << " leaves, " << r["octomap"]["memory_bytes"] << " B\n"
            << "  speedup " << r["speedup"].get<double>() << " (CPU time " << r["speedup_cpu"].get<double>() << ")"
            << "  memory_ratio " << r["memory_ratio"].get<double>()
            << "  cuboid_ratio " << r["cuboid_ratio"].get<double>() << "  agreement " << r["agreement"].get<double>()
            << "\n  point queries/s rmap " << r["point_query"]["rmap_per_s"].get<double>() << " octomap "
            << r["point_query"]["octomap_per_s"].get<double>()
            << "\n  fusion off (tolerance 0, exact walks): speedup " << r["fusion_off"]["speedup"].get<double>()
            << "  agreement " << r["fusion_off"]["agreement"].get<double>() << "\n"
            << "  cv_accuracy rmap " << r["cv_accuracy"]["rmap"].get<double>() << " octomap "
            << r["cv_accuracy"]["octomap"].get<double>();
  if (!r["truth_accuracy"].is_null()) {
    std::cout << "  truth_accuracy rmap " << r["truth_accuracy"]["rmap"].get<double>() << " octomap "
              << r["truth_accuracy"]["octomap"].get<double>();
  }
  std::cout << std::endl;
}

}  // namespace

int runMap3dBench(const Map3dBenchOptions& o) {
  std::cerr << "loading " << o.source << " ..." << std::endl;
  const BenchDataset data = loadBenchDataset(o.source, o.sim, o.shared_data_dir);
  uint64_t points = 0;
  for (const datasets::PointScan& s : data.scans) points += s.points_m.size();

  map3d::FusionParams fusion;
  if (o.fusion_tolerance >= 0.0f) fusion.tolerance_log_odds = o.fusion_tolerance;
  if (o.fuse_after_scans >= 0) fusion.fuse_after_scans = o.fuse_after_scans;
  map3d::OccupancyParams occupancy;
  occupancy.max_range_m = o.max_range_m;
  const bool exact_walks =
      o.free_space == "exact" || (o.free_space == "auto" && fusion.tolerance_log_odds == 0.0f);
  occupancy.free_space_tracing =
      exact_walks ? map3d::FreeSpaceTracing::kOctomapExact : map3d::FreeSpaceTracing::kStopAtFreed;

  json result = {{"dataset", data.name},
                 {"resolution_m", o.resolution_m},
                 {"scans", data.scans.size()},
                 {"points", points},
                 {"threads", o.threads},
                 {"fusion_tolerance", fusion.tolerance_log_odds},
                 {"fuse_after_scans", fusion.fuse_after_scans},
                 {"max_range_m", o.max_range_m},
                 {"free_space", exact_walks ? "exact" : "stop-at-freed"},
                 {"machine", machineJson()}};
  std::cout << data.name << " at " << o.resolution_m << " m, " << data.scans.size() << " scans, " << points
            << " points, " << o.threads << " thread(s), fusion tolerance " << fusion.tolerance_log_odds << std::endl;

  const bool beam = o.sensor_models == "beam" || o.sensor_models == "both";
  const bool endpoint = o.sensor_models == "endpoint" || o.sensor_models == "both";
  if (beam) {
    std::cerr << "beam model" << std::endl;
    occupancy.sensor_model = map3d::SensorModel::kBeam;
    const json r = compareOnce(data, o, occupancy, fusion, points);
    result["sensor_model"] = "beam";
    result.update(r);
    printRow("beam", r);
  }
  if (endpoint) {
    std::cerr << "endpoint model" << std::endl;
    occupancy.sensor_model = map3d::SensorModel::kEndpoint;
    json r = compareOnce(data, o, occupancy, fusion, points);
    printRow("endpoint", r);
    if (beam) {
      result["endpoint_model"] = r;
    } else {
      result["sensor_model"] = "endpoint";
      result.update(r);
    }
  }
  if (!o.json_out.empty()) {
    std::ofstream out(o.json_out);
    if (!out) {
      std::cerr << "cannot write " << o.json_out << std::endl;
      return 1;
    }
    out << result.dump(2) << std::endl;
  }
  return 0;
}

}  // namespace rmap::bench
