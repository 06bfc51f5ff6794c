// Several simulated robots stream at once into a real rmapd; the maps then
// answer occupancy queries the way the simulated world says they should.
#include <gtest/gtest.h>

#include <set>
#include <thread>

#include "api_helpers.h"
#include "client/http_client.h"
#include "client/sim_feed.h"
#include "rmapd_process.h"
#include "sim/truth.h"

namespace rmap::testing {
namespace {

TEST(StreamTruth, ConcurrentRobotsBuildMapsThatMatchTheSimulatedWorld) {
  TempDir dir("rmap-stream");
  RmapdProcess rmapd(dir.path() / "data");
  const client::SimScene scene = client::makeSimScene(7);

  client::SimFeedOptions shared;
  shared.server_url = rmapd.wsUrl();
  shared.robots = 3;
  shared.map_prefix = "shared";
  shared.shared_map = true;
  shared.rate_hz = 0.0;
  shared.max_clouds = 10;
  shared.duration = std::chrono::seconds(120);
  client::SimFeedOptions solo = shared;
  solo.robots = 2;
  solo.map_prefix = "solo";
  solo.shared_map = false;
  solo.robot_prefix = "solo-robot";
  solo.seed = 11;

  // Both feeds at once: five robots, three maps.
  client::SimFeedResult solo_result;
  std::thread solo_thread([&] { solo_result = client::runSimFeed(scene, solo); });
  const client::SimFeedResult shared_result = client::runSimFeed(scene, shared);
  solo_thread.join();
  for (const client::SimFeedResult* result : std::initializer_list<const client::SimFeedResult*>{&shared_result, &solo_result}) {
    EXPECT_TRUE(result->errors.empty()) << result->errors.front();
    EXPECT_EQ(result->clouds_acked, result->clouds_sent);
  }
  EXPECT_EQ(shared_result.clouds_sent, 30u);
  EXPECT_EQ(solo_result.clouds_sent, 20u);

  client::HttpClient http(rmapd.httpUrl());
  const nlohmann::json maps = getJson(http, "/v1/maps");
  std::set<std::string> names;
  for (const auto& m : maps["maps"]) names.insert(m["name"].get<std::string>());
  EXPECT_EQ(names, (std::set<std::string>{"shared", "solo-0", "solo-1"}));

  const nlohmann::json robots = getJson(http, "/v1/robots");
  ASSERT_EQ(robots["robots"].size(), 5u);
  for (const auto& r : robots["robots"]) EXPECT_EQ(r["last_seq"].get<uint64_t>(), 10u) << r.dump();
  // Poses reach the store within the map worker's flush period (0.5 s).
  nlohmann::json trajectory;
  for (int attempt = 0; attempt < 50; ++attempt) {
    trajectory = getJson(http, "/v1/robots/sim-robot-1/trajectory");
    if (trajectory["poses"].size() == 10u) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_EQ(trajectory["poses"].size(), 10u);

  // Query every 3rd cell centre of the building at the map resolution and
  // score the known answers against the world's voxels.
  const nlohmann::json info = getJson(http, "/v1/maps/shared");
  const double res = info["resolution_m"].get<double>();
  ASSERT_DOUBLE_EQ(res, 0.1);
  const Eigen::AlignedBox3d bounds = scene.world.bounds();
  std::vector<Eigen::Vector3d> points;
  for (double z = bounds.min().z() + 0.05; z < bounds.max().z(); z += 3 * res) {
    for (double y = bounds.min().y() + 0.05; y < bounds.max().y(); y += 3 * res) {
      for (double x = bounds.min().x() + 0.05; x < bounds.max().x(); x += 3 * res) {
        const Eigen::Vector3d cell(std::floor(x / res), std::floor(y / res), std::floor(z / res));
        points.push_back((cell + Eigen::Vector3d::Constant(0.5)) * res);
      }
    }
  }
  const v1::OccupancyBatchResponse answers = batchQuery(http, "shared", points);
  // A ray ends on a voxel face, so range noise puts about half the endpoints
  // in the free cell in front of the surface: an occupied cell counts as
  // right when the surface is within one cell of it.
  const auto surface_within_one_cell = [&](const Eigen::Vector3d& p) {
    if (sim::trueOccupied(scene.world, p)) return true;
    for (int axis = 0; axis < 3; ++axis) {
      for (const double step : {-res, res}) {
        if (sim::trueOccupied(scene.world, p + step * Eigen::Vector3d::Unit(axis))) return true;
      }
    }
    return false;
  };
  size_t occupied = 0, occupied_right = 0, occupied_exact = 0, free = 0, free_right = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    if (answers.states(static_cast<int>(i)) == v1::OCCUPIED) {
      ++occupied;
      occupied_exact += sim::trueOccupied(scene.world, points[i]);
      occupied_right += surface_within_one_cell(points[i]);
    } else if (answers.states(static_cast<int>(i)) == v1::FREE) {
      ++free;
      free_right += !sim::trueOccupied(scene.world, points[i]);
    }
  }
  std::cout << "known " << occupied + free << " of " << points.size() << " sampled cells; occupied precision "
            << double(occupied_right) / occupied << " (same cell " << double(occupied_exact) / occupied
            << "), free precision " << double(free_right) / free << "\n";
  ASSERT_GT(occupied, 200u);
  ASSERT_GT(free, 5000u);
  // Surfaces seen at grazing angles and sensor noise leave some cells wrong;
  // the bulk must match the world.
  EXPECT_GT(double(occupied_right) / occupied, 0.97);
  EXPECT_GT(double(free_right) / free, 0.97);

  // The single-point endpoint gives the batch's answers.
  for (size_t i = 0; i < points.size(); i += points.size() / 25) {
    const Eigen::Vector3d& p = points[i];
    const nlohmann::json one = getJson(http, "/v1/maps/shared/occupancy?x=" + std::to_string(p.x()) +
                                                 "&y=" + std::to_string(p.y()) + "&z=" + std::to_string(p.z()));
    const char* expected = answers.states(static_cast<int>(i)) == v1::OCCUPIED ? "occupied"
                           : answers.states(static_cast<int>(i)) == v1::FREE ? "free"
                                                                              : "unknown";
    EXPECT_EQ(one["state"], expected) << p.transpose();
    EXPECT_NEAR(one["probability"].get<double>(), answers.probabilities(static_cast<int>(i)), 1e-6);
  }
  // Far outside anything observed.
  EXPECT_EQ(getJson(http, "/v1/maps/shared/occupancy?x=500&y=500&z=500")["state"], "unknown");
}

}  // namespace
}  // namespace rmap::testing
