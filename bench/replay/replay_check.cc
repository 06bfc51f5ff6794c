#include "replay/replay_check.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "app/grid2d_export.h"
#include "client/http_client.h"
#include "map3d/bench_dataset.h"
#include "map3d/cuboid_map.h"
#include "rmap/v1/map_api.pb.h"
#include "slam2d/slam2d.h"
#include "slam2d/slam2d_dataset.h"

namespace rmap::bench {
namespace {

using json = nlohmann::json;
constexpr size_t kBatchPoints = 200'000;
constexpr uint64_t kMaxKnownCellQueries = 500'000;

json getJson(client::HttpClient& http, const std::string& target) {
  const client::HttpResponse r = http.get(target);
  if (r.status != 200) throw std::runtime_error("GET " + target + ": " + std::to_string(r.status) + " " + r.body);
  return json::parse(r.body);
}

std::string getBody(client::HttpClient& http, const std::string& target) {
  const client::HttpResponse r = http.get(target);
  if (r.status != 200) throw std::runtime_error("GET " + target + ": " + std::to_string(r.status) + " " + r.body);
  return r.body;
}

v1::CellState toProto(map3d::CellState s) {
  switch (s) {
    case map3d::CellState::kFree: return v1::FREE;
    case map3d::CellState::kOccupied: return v1::OCCUPIED;
    default: return v1::UNKNOWN;
  }
}

json statsJson(const map3d::MapStats& s) {
  return {{"cuboids", s.cuboids}, {"known_cells", s.known_cells}, {"occupied_cells", s.occupied_cells},
          {"blocks", s.blocks}, {"hot_blocks", s.hot_blocks}};
}

/// Query points: every step-th cell centre of the map's bounds and every known cell (evenly sampled).
std::vector<Eigen::Vector3d> queryPoints(const map3d::CuboidMap& map, int step) {
  std::vector<Eigen::Vector3d> points;
  map3d::CellKey lo, hi;
  if (!map.bounds(lo, hi)) return points;
  const map3d::Grid& grid = map.grid();
  for (int32_t z = lo.z; z <= hi.z; z += step)
    for (int32_t y = lo.y; y <= hi.y; y += step)
      for (int32_t x = lo.x; x <= hi.x; x += step) points.push_back(grid.center(map3d::CellKey{x, y, z}));
  const uint64_t stride = std::max<uint64_t>(1, map.stats().known_cells / kMaxKnownCellQueries);
  uint64_t n = 0;
  map.forEachKnownCell([&](const map3d::CellKey& c, float) {
    if (n++ % stride == 0) points.push_back(grid.center(c));
  });
  return points;
}

json check3d(const ReplayCheckOptions& o, client::HttpClient& http, bool& equal) {
  const BenchDataset data = loadBenchDataset(o.scans_source, SimOptions{}, o.shared_data_dir);
  // As rmap-bench map3d builds its map (library defaults: beam model, stop-at-freed walks, fusion 0.25).
  map3d::CuboidMap map(o.resolution_m, map3d::OccupancyParams{}, map3d::FusionParams{});
  const map3d::InsertOptions insert{1, map3d::InvalidPoints::kSkip};
  for (const datasets::PointScan& s : data.scans) {
    if (!s.points_m.empty()) map.insertScan(s.sensor_origin_m, s.points_m, insert);
  }
  const map3d::MapStats unfused = map.stats();
  map3d::CuboidMap fused_map(o.resolution_m, map3d::OccupancyParams{}, map3d::FusionParams{});
  for (const datasets::PointScan& s : data.scans) {
    if (!s.points_m.empty()) fused_map.insertScan(s.sensor_origin_m, s.points_m, insert);
  }
  fused_map.fuseAll(1);
  const map3d::MapStats fused = fused_map.stats();

  const json server = getJson(http, "/v1/maps/" + o.map);
  const uint64_t server_cuboids = server["cuboids"].get<uint64_t>();
  const bool cells_equal = server["known_cells"].get<uint64_t>() == unfused.known_cells &&
                           server["occupied_cells"].get<uint64_t>() == unfused.occupied_cells;
  const std::string cuboids_match = server_cuboids == unfused.cuboids ? "unfused"
                                    : server_cuboids == fused.cuboids ? "fused"
                                                                      : "neither";
  // The server answers from the map as it holds it: fused blocks answer the cuboid's value.
  const map3d::CuboidMap& reference = cuboids_match == "fused" ? fused_map : map;

  const std::vector<Eigen::Vector3d> points = queryPoints(map, std::max(1, o.grid_step_cells));
  uint64_t same_state = 0, same_probability = 0, occupied = 0;
  double max_probability_diff = 0.0;
  for (size_t begin = 0; begin < points.size(); begin += kBatchPoints) {
    const size_t end = std::min(points.size(), begin + kBatchPoints);
    v1::OccupancyBatchRequest request;
    for (size_t i = begin; i < end; ++i)
      for (int a = 0; a < 3; ++a) request.add_xyz_m(points[i][a]);
    const client::HttpResponse r = http.post("/v1/maps/" + o.map + "/occupancy:batch", request.SerializeAsString(),
                                             "application/x-protobuf");
    v1::OccupancyBatchResponse response;
    if (r.status != 200 || !response.ParseFromString(r.body) ||
        response.states_size() != static_cast<int>(end - begin)) {
      throw std::runtime_error("occupancy:batch: " + std::to_string(r.status) + " " + r.body.substr(0, 200));
    }
    for (size_t i = begin; i < end; ++i) {
      const map3d::CellQuery q = reference.query(points[i]);
      const int k = static_cast<int>(i - begin);
      same_state += response.states(k) == toProto(q.state);
      occupied += q.state == map3d::CellState::kOccupied;
      const double d = std::abs(static_cast<double>(response.probabilities(k)) - static_cast<float>(q.probability));
      same_probability += d == 0.0;
      max_probability_diff = std::max(max_probability_diff, d);
    }
  }
  equal = cells_equal && cuboids_match != "neither" && same_state == points.size();
  std::printf("3D %s at %.3f m: server %llu cuboids, %llu known, %llu occupied cells | offline %llu known, %llu "
              "occupied, %llu cuboids unfused, %llu fused (the benchmark's count) -> server count is the %s one\n",
              o.scans_source.c_str(), o.resolution_m, (unsigned long long)server_cuboids,
              (unsigned long long)server["known_cells"].get<uint64_t>(),
              (unsigned long long)server["occupied_cells"].get<uint64_t>(), (unsigned long long)unfused.known_cells,
              (unsigned long long)unfused.occupied_cells, (unsigned long long)unfused.cuboids,
              (unsigned long long)fused.cuboids, cuboids_match.c_str());
  std::printf("   occupancy queries: %zu, same state %llu (%llu occupied), same probability %llu, max |dp| %.3g -> %s\n",
              points.size(), (unsigned long long)same_state, (unsigned long long)occupied,
              (unsigned long long)same_probability, max_probability_diff, equal ? "EQUAL" : "DIFFERENT");
  return {{"source", o.scans_source},
          {"resolution_m", o.resolution_m},
          {"server", {{"cuboids", server_cuboids}, {"known_cells", server["known_cells"]},
                      {"occupied_cells", server["occupied_cells"]}}},
          {"offline_unfused", statsJson(unfused)},
          {"offline_fused", statsJson(fused)},
          {"server_cuboids_match", cuboids_match},
          {"queries", points.size()},
          {"same_state", same_state},
          {"occupied_answers", occupied},
          {"same_probability", same_probability},
          {"max_probability_diff", max_probability_diff},
          {"equal", equal}};
}

/// The offline SLAM's finest grid as the server's exports read it.
class OfflineGrid : public app::Grid2dSource {
 public:
  explicit OfflineGrid(const slam2d::Slam2d& slam) : slam_(slam) {}
  double resolutionM() const override { return slam_.grid().resolution_m(); }
  Eigen::AlignedBox2i knownCells() const override { return slam_.grid().knownCells(); }
  float probability(const Eigen::Vector2i& cell) const override { return slam_.grid().probability(cell); }
  float reflectivity(const Eigen::Vector2i& cell) const override {
    const slam2d::ReflectivityCell r = slam_.grid().reflectivity(cell);
    return r.count > 0 ? static_cast<float>(r.mean) : std::numeric_limits<float>::quiet_NaN();
  }

 private:
  const slam2d::Slam2d& slam_;
};

json check2d(const ReplayCheckOptions& o, client::HttpClient& http, bool& equal) {
  const Slam2dDataset data = loadSlam2dDataset(o.log_path, Slam2dSourceOptions{});
  // rmap-bench slam2d with --loop-closure on: the engine's defaults, which rmapd's SLAM uses.
  slam2d::Slam2dOptions options;
  options.loop_closure.enabled = true;
  slam2d::Slam2d slam(options);
  size_t rejected = 0;
  for (const Slam2dInput& in : data.inputs) {
    try {
      slam.addScan("robot", in.scan, in.odometry);
    } catch (const std::invalid_argument&) {
      ++rejected;
    }
  }
  const OfflineGrid grid(slam);
  const std::string offline_pgm = app::exportGridPgm(grid);
  const std::string offline_yaml = app::exportGridYaml(grid, "grid2d.pgm");
  const std::string server_pgm = getBody(http, "/v1/maps/" + o.map + "/grid2d.pgm");
  const std::string server_yaml = getBody(http, "/v1/maps/" + o.map + "/grid2d.yaml");
  size_t differing = 0;
  if (server_pgm.size() == offline_pgm.size()) {
    for (size_t i = 0; i < server_pgm.size(); ++i) differing += server_pgm[i] != offline_pgm[i];
  }
  // The server rewrites a stored pose only once a correction moved it by half a 3D cell.
  const std::vector<slam2d::StampedPose2> offline = slam.trajectory("robot");
  const json poses = getJson(http, "/v1/robots/" + o.robot_id + "/trajectory?limit=1000000")["poses"];
  double max_pose_diff_m = 0.0;
  size_t matched = 0;
  size_t first_differing = std::numeric_limits<size_t>::max();  // scan index
  for (const json& p : poses) {
    // seq k is the k-th scan the replay sent, the k-th of the offline trajectory (no scan was refused).
    const size_t k = p["seq"].get<size_t>() - 1;
    if (k >= offline.size() || p["stamp_ns"].get<int64_t>() != offline[k].stamp_ns) continue;
    ++matched;
    const double dx = p["position"][0].get<double>() - offline[k].pose.x_m;
    const double dy = p["position"][1].get<double>() - offline[k].pose.y_m;
    max_pose_diff_m = std::max(max_pose_diff_m, std::hypot(dx, dy));
    if (std::hypot(dx, dy) > 1e-6) first_differing = std::min(first_differing, k);
  }
  if (server_pgm != offline_pgm) {
    std::printf("   PGM headers: server '%s', offline '%s'\n", server_pgm.substr(0, server_pgm.find("255")).c_str(),
                offline_pgm.substr(0, offline_pgm.find("255")).c_str());
  }
  const bool pgm_equal = server_pgm == offline_pgm;
  // rmapd rewrites a stored pose after a loop-closure correction only once it moved by half a 3D
  // cell (map_worker.cc), so stored poses may lag the corrected ones by up to that much.
  const double tolerance_m = getJson(http, "/v1/maps/" + o.map)["resolution_m"].get<double>() / 2;
  equal = pgm_equal && server_yaml == offline_yaml && matched == offline.size() && poses.size() == offline.size() &&
          max_pose_diff_m <= tolerance_m;
  std::printf("2D %s: %zu scans (%zu refused offline), %zu keyframes; map_server export: PGM %zu bytes, %s (%zu "
              "bytes differ), YAML %s; trajectory %zu/%zu poses at the same stamps (server %zu), max position difference %.4f m "
              "(rmapd rewrites poses moved by >= %.3f m) -> %s\n",
              o.log_path.c_str(), data.inputs.size(), rejected, slam.keyframeCount(), server_pgm.size(),
              pgm_equal ? "identical" : "DIFFERENT", differing, server_yaml == offline_yaml ? "identical" : "DIFFERENT",
              matched, offline.size(), poses.size(), max_pose_diff_m, tolerance_m, equal ? "EQUAL" : "DIFFERENT");
  return {{"log", o.log_path},
          {"scans", data.inputs.size()},
          {"refused_offline", rejected},
          {"keyframes", slam.keyframeCount()},
          {"pgm_bytes", server_pgm.size()},
          {"pgm_identical", pgm_equal},
          {"pgm_bytes_differing", differing},
          {"yaml_identical", server_yaml == offline_yaml},
          {"trajectory_poses", {{"server", poses.size()}, {"offline", offline.size()}, {"same_stamp", matched}}},
          {"max_position_diff_m", max_pose_diff_m},
          {"position_tolerance_m", tolerance_m},
          {"first_differing_scan", first_differing == std::numeric_limits<size_t>::max() ? json(nullptr) : json(first_differing)},
          {"equal", equal}};
}

}  // namespace

int runReplayCheck(const ReplayCheckOptions& o) {
  client::HttpClient http(o.server_url, o.token, std::chrono::milliseconds(120000));
  json out = {{"server", o.server_url}, {"map", o.map}};
  bool equal = true;
  if (!o.scans_source.empty()) {
    bool e = false;
    out["map3d"] = check3d(o, http, e);
    equal = equal && e;
  }
  if (!o.log_path.empty()) {
    bool e = false;
    out["slam2d"] = check2d(o, http, e);
    equal = equal && e;
  }
  out["equal"] = equal;
  if (!o.json_out.empty()) {
    std::ofstream file(o.json_out);
    file << out.dump(2) << "\n";
    if (!file) throw std::runtime_error("cannot write " + o.json_out);
  }
  return equal ? 0 : 1;
}

}  // namespace rmap::bench
