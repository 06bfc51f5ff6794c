// A simulated robot with a 2D laser (client::Laser2dRobot, the sim feed's)
// streams scans (intensities, noisy odometry) into a real rmapd: the PoseEstimates it gets back follow the true path, the
// reflectivity tiles show the building's reflective markers, the map_server
// export matches the occupancy tiles, and a kill -9 replays to the same map.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <mutex>
#include <sstream>

#include "api_helpers.h"
#include "image_files.h"
#include "client/http_client.h"
#include "client/laser2d_robot.h"
#include "client/robot_client.h"
#include "rmapd_process.h"
#include "sim/building.h"
#include "sim/trajectory.h"

namespace rmap::testing {
namespace {

constexpr double kLaserHeight_m = 1.0;

TEST(Slam2dStream, ScansGetPoseEstimatesAndMakeTheTwoDimensionalLayers) {
  TempDir dir("rmap-slam2d");
  auto rmapd = std::make_unique<RmapdProcess>(dir.path() / "data");

  // The building, with its reflective tape markers reaching the laser's plane.
  sim::BuildingOptions building;
  building.max_furniture_per_room = 1;
  sim::BuildingLayout layout;
  sim::VoxelWorld world = sim::makeBuilding(building, 3, &layout);
  ASSERT_FALSE(layout.markers.empty());
  client::extendMarkersToLaserPlane(world, layout, building.floor_height_m, kLaserHeight_m);
  sim::TrajectoryOptions path;
  path.sensor_height_m = kLaserHeight_m;
  path.num_poses = 160;
  path.step_m = 0.26;
  client::Laser2dRobotOptions laser;
  laser.laser = sim::Laser2dModel::sickLike();
  laser.sensor_name = "front";
  laser.mount_height_m = kLaserHeight_m;
  client::Laser2dRobot simulated(world, sim::planTrajectory(world, path, 5), laser, 11);

  client::RobotClientOptions options;
  options.server_url = rmapd->wsUrl();
  options.hello.set_robot_id("walker");
  options.hello.set_map("floor");
  *options.hello.add_sensors() = simulated.sensor();
  std::mutex mutex;
  std::map<uint64_t, v1::PoseEstimate> estimates;
  client::RobotClient robot(options);
  robot.onPose([&](const v1::PoseEstimate& e) {
    std::lock_guard lock(mutex);
    estimates[e.seq()] = e;
  });
  robot.connect();

  // One pass over the tour (wheel odometry drifting 5 % per step plus a heading error).
  std::map<uint64_t, Eigen::Vector3d> truth;
  for (int k = 0; k < path.num_poses; ++k) {
    client::Laser2dStep step = simulated.next();
    v1::RobotMessage m;
    *m.mutable_scan() = std::move(step.scan);
    m.mutable_scan()->set_stamp_ns(static_cast<int64_t>(k) * 100'000'000);
    truth[robot.send(m)] = step.base_truth;
  }
  ASSERT_TRUE(robot.waitAllAcked(std::chrono::seconds(120)));

  // Every scan got its estimate before its ack, within 0.1 m of the truth.
  {
    std::lock_guard lock(mutex);
    ASSERT_EQ(estimates.size(), truth.size());
    double worst_m = 0.0, worst_rad = 0.0;
    for (const auto& [seq, base] : truth) {
      const v1::PoseEstimate& e = estimates.at(seq);
      EXPECT_EQ(e.stamp_ns(), static_cast<int64_t>(seq - 1) * 100'000'000);
      const Eigen::Vector2d p(e.pose().position_m().x(), e.pose().position_m().y());
      const double yaw = 2 * std::atan2(e.pose().orientation().z(), e.pose().orientation().w());
      worst_m = std::max(worst_m, (p - base.head<2>()).norm());
      worst_rad = std::max(worst_rad, std::abs(std::remainder(yaw - base.z(), 2 * M_PI)));
    }
    EXPECT_LT(worst_m, 0.1);
    EXPECT_LT(worst_rad, 0.05);
    std::printf("[ estimates ] %zu scans, worst error %.3f m, %.4f rad\n", truth.size(), worst_m, worst_rad);
  }

  client::HttpClient http(rmapd->httpUrl());
  const nlohmann::json info = getJson(http, "/v1/maps/floor/layers");
  EXPECT_EQ(info["scans"].get<size_t>(), truth.size());
  EXPECT_EQ(info["tile_px"].get<int>(), 256);
  const double r = info["resolution_m"].get<double>();
  ASSERT_GT(r, 0.0);
  EXPECT_DOUBLE_EQ(info["extent_max_m"][0].get<double>(), 32768 * r);

  // The robot's pose and the planar cloud in the 3D map.
  const nlohmann::json walker = getJson(http, "/v1/robots/walker");
  ASSERT_TRUE(walker["pose"].is_object()) << walker.dump();
  EXPECT_NEAR(walker["pose"]["position"][0].get<double>(), truth.rbegin()->second.x(), 0.1);
  const nlohmann::json map3d = getJson(http, "/v1/maps/floor");
  EXPECT_GT(map3d["occupied_cells"].get<int64_t>(), 100);
  EXPECT_NEAR(map3d["bounds"]["min"][2].get<double>(), kLaserHeight_m, 0.2);

  // Reflectivity: marker cells are brighter than the wall cells around them.
  LayerCells reflectivity(http, "floor", "reflectivity");
  double marker_sum = 0.0, wall_sum = 0.0;
  int marker_n = 0, wall_n = 0;
  const auto cellOf = [&](double v) { return static_cast<int>(std::floor(v / r)); };
  for (const Eigen::AlignedBox3d& m : layout.markers) {
    // The marker faces the corridor; walls lie on the same line beyond its ends.
    const double y = m.center().y();
    for (double x = m.min().x() - 1.0; x < m.max().x() + 1.0; x += r) {
      const bool on_marker = x > m.min().x() + 2 * r && x < m.max().x() - 2 * r;
      const bool off_marker = x < m.min().x() - 3 * r || x > m.max().x() + 3 * r;
      if (!on_marker && !off_marker) continue;
      // The brightest cell across the wall's thickness at this x.
      int best = -1;
      for (int dy = -2; dy <= 2; ++dy) {
        const auto [grey, alpha] = reflectivity.at(cellOf(x), cellOf(y) + dy);
        if (alpha == 255) best = std::max(best, int{grey});
      }
      if (best < 0) continue;
      (on_marker ? marker_sum : wall_sum) += best;
      ++(on_marker ? marker_n : wall_n);
    }
  }
  ASSERT_GT(marker_n, 10);
  ASSERT_GT(wall_n, 10);
  std::printf("[ reflectivity ] markers %.1f (%d cells), walls %.1f (%d cells) of 255\n", marker_sum / marker_n,
              marker_n, wall_sum / wall_n, wall_n);
  // Markers are ρ 0.95, the corridor walls 0.45–0.80.
  EXPECT_GT(marker_sum / marker_n, 1.2 * wall_sum / wall_n);

  // map_server export: the same occupancy as the tiles, pixel for pixel.
  const client::HttpResponse yaml_response = http.get("/v1/maps/floor/grid2d.yaml");
  ASSERT_EQ(yaml_response.status, 200);
  const std::map<std::string, std::string> yaml = parseYaml(yaml_response.body);
  EXPECT_EQ(yaml.at("image"), "grid2d.pgm");
  EXPECT_DOUBLE_EQ(std::stod(yaml.at("resolution")), r);
  EXPECT_EQ(yaml.at("negate"), "0");
  EXPECT_EQ(yaml.at("occupied_thresh"), "0.65");
  EXPECT_EQ(yaml.at("free_thresh"), "0.196");
  double origin_x = 0, origin_y = 0;
  ASSERT_EQ(std::sscanf(yaml.at("origin").c_str(), "[%lf, %lf", &origin_x, &origin_y), 2);
  const client::HttpResponse pgm = http.get("/v1/maps/floor/grid2d.pgm");
  ASSERT_EQ(pgm.status, 200);
  int width = 0, height = 0, maxval = 0, header = 0;
  ASSERT_EQ(std::sscanf(pgm.body.c_str(), "P5\n%d %d\n%d\n%n", &width, &height, &maxval, &header), 3);
  ASSERT_EQ(maxval, 255);
  ASSERT_EQ(pgm.body.size(), static_cast<size_t>(header + width * height));
  EXPECT_NEAR(origin_x, info["known_bounds"]["min"][0].get<double>(), 1e-9);
  EXPECT_NEAR(origin_x + width * r, info["known_bounds"]["max"][0].get<double>(), 1e-9);
  EXPECT_NEAR(origin_y + height * r, info["known_bounds"]["max"][1].get<double>(), 1e-9);
  LayerCells occupancy(http, "floor", "occupancy");
  const int x0 = static_cast<int>(std::lround(origin_x / r)), y0 = static_cast<int>(std::lround(origin_y / r));
  size_t checked = 0, occupied = 0, mismatched = 0;
  for (int row = 0; row < height; ++row) {
    for (int col = 0; col < width; ++col) {
      const uint8_t value = static_cast<uint8_t>(pgm.body[header + row * width + col]);
      const auto [grey, alpha] = occupancy.at(x0 + col, y0 + height - 1 - row);
      const double p = 1.0 - grey / 255.0;
      uint8_t expected = 205;
      if (alpha == 255 && p >= 0.655) expected = 0;
      if (alpha == 255 && p <= 0.19) expected = 254;
      const bool near_threshold = alpha == 255 && (std::abs(p - 0.65) < 0.006 || std::abs(p - 0.196) < 0.006);
      if (near_threshold) continue;  // the tile's 8-bit grey cannot tell these apart
      ++checked;
      occupied += value == 0;
      mismatched += value != expected;
    }
  }
  EXPECT_EQ(mismatched, 0u) << "of " << checked;
  EXPECT_GT(occupied, 200u);

  // Caching: the same version answers 304.
  const client::HttpResponse tile = http.get("/v1/maps/floor/layers/occupancy/0/0/0.png");
  ASSERT_EQ(tile.status, 200);
  EXPECT_EQ(http.get("/v1/maps/floor/layers/occupancy/0/0/0.png", {{"If-None-Match", tile.header("etag")}}).status,
            304);

  // Bad layer requests.
  for (const char* target : {"/v1/maps/floor/layers/occupancy/11/0/0.png", "/v1/maps/floor/layers/occupancy/1/2/0.png",
                             "/v1/maps/floor/layers/occupancy/1/0/-1.png", "/v1/maps/floor/layers/occupancy/a/0/0.png",
                             "/v1/maps/floor/layers/occupancy/0/0/0"}) {
    const client::HttpResponse bad = http.get(target);
    EXPECT_EQ(bad.status, 400) << target;
    EXPECT_EQ(nlohmann::json::parse(bad.body)["error"]["code"], "invalid_argument") << target;
  }
  EXPECT_EQ(http.get("/v1/maps/floor/layers/height/0/0/0.png").status, 404);
  EXPECT_EQ(nlohmann::json::parse(http.get("/v1/maps/nope/layers/occupancy/0/0/0.png").body)["error"]["code"],
            "map_not_found");
  {
    client::RobotClientOptions plain;
    plain.server_url = rmapd->wsUrl();
    plain.hello.set_robot_id("cloud-only");
    plain.hello.set_map("no-laser");
    client::RobotClient other(plain);
    other.connect();  // creates the map, which has no 2D layer
  }
  for (const char* target : {"/v1/maps/no-laser/layers", "/v1/maps/no-laser/layers/occupancy/0/0/0.png",
                             "/v1/maps/no-laser/grid2d.pgm", "/v1/maps/no-laser/grid2d.yaml"}) {
    const client::HttpResponse none = http.get(target);
    EXPECT_EQ(none.status, 404) << target;
    EXPECT_EQ(nlohmann::json::parse(none.body)["error"]["code"], "layer_not_found") << target;
  }
  const std::string metrics = http.get("/metrics").body;
  EXPECT_EQ(metricValue(metrics, "rmap_slam2d_scans_total"), static_cast<double>(truth.size()));
  EXPECT_EQ(metricValue(metrics, "rmap_pose_estimates_sent_total"), static_cast<double>(truth.size()));

  // kill -9 and restart: the replayed log rebuilds the same 2D map.
  const std::string pgm_before = pgm.body;
  const uint64_t version_before = info["version"].get<uint64_t>();
  rmapd->kill9();
  rmapd.reset();
  rmapd = std::make_unique<RmapdProcess>(dir.path() / "data");
  client::HttpClient again(rmapd->httpUrl());
  const nlohmann::json replayed = getJson(again, "/v1/maps/floor/layers");
  EXPECT_EQ(replayed["version"].get<uint64_t>(), version_before);
  EXPECT_EQ(replayed["scans"].get<size_t>(), truth.size());
  EXPECT_TRUE(again.get("/v1/maps/floor/grid2d.pgm").body == pgm_before);
}

}  // namespace
}  // namespace rmap::testing
