// Two simulated robots with 2D lasers (client::Laser2dRobot, intensities and
// drifting odometry) map one building from opposite ends of the same tour, so
// each drives where the other has been: rmapd finds loop closures between
// them, serves them on GET /v1/loop-closures and pushes them on the viewer
// stream, and the trajectories it serves after the pose graph's corrections
// are closer to the truth than the estimates the robots got live. Two lidar
// robots' panorama closures carry a relative pose that matches the truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <mutex>
#include <set>
#include <tuple>
#include <thread>

#include "api_helpers.h"
#include "client/http_client.h"
#include "client/laser2d_robot.h"
#include "client/robot_client.h"
#include "client/sim_feed.h"
#include "rmapd_process.h"
#include "sim/building.h"
#include "sim/trajectory.h"
#include "viewer_stream.h"

namespace rmap::testing {
namespace {

constexpr double kCrossingLaserHeight_m = 1.0;
constexpr int64_t kStepNs = 100'000'000;

/// The tour driven the other way: reversed, each pose turned to face its new direction of travel.
std::vector<Eigen::Isometry3d> reversedTour(std::vector<Eigen::Isometry3d> tour) {
  std::reverse(tour.begin(), tour.end());
  for (Eigen::Isometry3d& pose : tour) pose.rotate(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()));
  return tour;
}

/// The simulated building of the 2D-laser tests (seed 3, its markers reaching the laser plane)
/// and a tour of `poses` poses 0.26 m apart through it.
struct LaserWorld {
  sim::VoxelWorld world;
  std::vector<Eigen::Isometry3d> tour;
};
LaserWorld laserWorld(int poses) {
  sim::BuildingOptions building;
  building.max_furniture_per_room = 1;
  sim::BuildingLayout layout;
  LaserWorld out{sim::makeBuilding(building, 3, &layout), {}};
  client::extendMarkersToLaserPlane(out.world, layout, building.floor_height_m, kCrossingLaserHeight_m);
  sim::TrajectoryOptions path;
  path.sensor_height_m = kCrossingLaserHeight_m;
  path.num_poses = poses;
  path.step_m = 0.26;
  out.tour = sim::planTrajectory(out.world, path, 5);
  return out;
}

/// A SICK-like scanner at the laser height.
client::Laser2dRobotOptions sickLaser() {
  client::Laser2dRobotOptions laser;
  laser.laser = sim::Laser2dModel::sickLike();
  laser.mount_height_m = kCrossingLaserHeight_m;
  return laser;
}

struct SimRobot {
  std::string id;
  client::Laser2dRobot sim;
  /// Where the robot's odometry frame lies in the map (its guess of its start is this far off).
  Eigen::Vector3d odometry_offset = Eigen::Vector3d::Zero();
  std::unique_ptr<client::RobotClient> client;
  std::mutex mutex;
  std::map<int64_t, Eigen::Vector3d> truth;           ///< by stamp: base x, y, yaw
  std::map<int64_t, Eigen::Vector3d> live_estimates;  ///< by stamp, as the robot got them
};

Eigen::Vector3d planarOf(const nlohmann::json& position, const nlohmann::json& orientation) {
  const double w = orientation[0].get<double>(), z = orientation[3].get<double>();
  return {position[0].get<double>(), position[1].get<double>(), 2 * std::atan2(z, w)};
}

/// The error (m, rad) of a closure's planar `relative_pose` (the query's pose in the match's
/// frame) against the one between the two true poses (x, y, θ).
std::pair<double, double> relativePoseError(const nlohmann::json& relative_pose, const Eigen::Vector3d& query_truth,
                                            const Eigen::Vector3d& match_truth) {
  const Eigen::Vector3d measured = planarOf(relative_pose["position"], relative_pose["orientation"]);
  const Eigen::Vector2d shift = Eigen::Rotation2Dd(-match_truth.z()) * (query_truth - match_truth).head<2>();
  const double turn = std::remainder(measured.z() - (query_truth.z() - match_truth.z()), 2 * M_PI);
  return {(measured.head<2>() - shift).norm(), std::abs(turn)};
}

/// Connects `robot` to `map`; its live estimates are kept as they come.
void connect(SimRobot& robot, const std::string& server_url, const std::string& map) {
  client::RobotClientOptions options;
  options.server_url = server_url;
  options.hello.set_robot_id(robot.id);
  options.hello.set_map(map);
  *options.hello.add_sensors() = robot.sim.sensor();
  robot.client = std::make_unique<client::RobotClient>(options);
  robot.client->onPose([r = &robot](const v1::PoseEstimate& e) {
    const double yaw = 2 * std::atan2(e.pose().orientation().z(), e.pose().orientation().w());
    std::lock_guard lock(r->mutex);
    r->live_estimates[e.stamp_ns()] = {e.pose().position_m().x(), e.pose().position_m().y(), yaw};
  });
  robot.client->connect();
}

/// Simulates the robot's next scan, sends it stamped `stamp_ns` and keeps its true pose.
void sendNextScan(SimRobot& robot, int64_t stamp_ns) {
  client::Laser2dStep step = robot.sim.next();
  if (robot.odometry_offset != Eigen::Vector3d::Zero()) {
    v1::Pose2& odometry = *step.scan.mutable_odometry();
    const Eigen::Vector3d& o = robot.odometry_offset;
    const Eigen::Rotation2Dd turn(o.z());
    const Eigen::Vector2d p = turn * Eigen::Vector2d(odometry.x_m(), odometry.y_m()) + o.head<2>();
    odometry.set_x_m(p.x());
    odometry.set_y_m(p.y());
    odometry.set_theta_rad(odometry.theta_rad() + o.z());
  }
  v1::RobotMessage m;
  *m.mutable_scan() = std::move(step.scan);
  m.mutable_scan()->set_stamp_ns(stamp_ns);
  {
    std::lock_guard lock(robot.mutex);
    robot.truth[stamp_ns] = step.base_truth;
  }
  robot.client->send(m);
}

/// Mean translational error (m) of `poses` against `truth` over the stamps both hold.
double meanError(const std::map<int64_t, Eigen::Vector3d>& poses, const std::map<int64_t, Eigen::Vector3d>& truth,
                 size_t* matched = nullptr) {
  double sum = 0.0;
  size_t n = 0;
  for (const auto& [stamp, p] : poses) {
    const auto t = truth.find(stamp);
    if (t == truth.end()) continue;
    sum += (p.head<2>() - t->second.head<2>()).norm();
    ++n;
  }
  if (matched) *matched = n;
  return n ? sum / static_cast<double>(n) : INFINITY;
}

TEST(LoopClosure, TwoRobotsCrossingOnOneMapCloseALoopAndTheirTrajectoriesAreCorrected) {
  TempDir dir("rmap-loop");
  auto rmapd = std::make_unique<RmapdProcess>(dir.path() / "data");

  const LaserWorld scene = laserWorld(200);
  const sim::VoxelWorld& world = scene.world;
  const std::vector<Eigen::Isometry3d>& tour = scene.tour;
  client::Laser2dRobotOptions laser = sickLaser();
  // Drift the SLAM's front end has to live with until a loop closes.
  laser.odometry_forward_sigma = 0.1;
  laser.odometry_heading_sigma_rad = 0.04;

  // West's idea of where it starts is off by 0.64 m and 4.6°: until the robots meet, it maps its end
  // of the building that far off; the closures with east's map pull it back.
  SimRobot a{"east", client::Laser2dRobot(world, tour, laser, 11), {0, 0, 0}, nullptr, {}, {}, {}};
  SimRobot b{"west", client::Laser2dRobot(world, reversedTour(tour), laser, 12), {0.5, -0.4, 0.08}, nullptr, {}, {},
             {}};
  for (SimRobot* r : {&a, &b}) connect(*r, rmapd->wsUrl(), "shared");
  // A viewer of the map (it exists once a robot said Hello).
  ViewerStream viewer(rmapd->port(), "shared");
  std::vector<nlohmann::json> pushed;  // loop closures seen on the viewer stream
  std::atomic<bool> watching{true};
  std::thread watcher([&] {
    // Until the test is done and the stream has been quiet for a while (a timed-out read
    // cancels the stream, so there is one).
    while (std::optional<nlohmann::json> frame = viewer.next(std::chrono::seconds(3))) {
      const bool loop = frame->is_object() && frame->value("type", "") == "loop_closure";
      if (loop) pushed.push_back(std::move(*frame));
      if (!watching && !loop) break;
    }
  });
  const auto start = std::chrono::steady_clock::now();
  for (size_t k = 0; k < tour.size(); ++k) {
    for (SimRobot* r : {&a, &b}) {
      sendNextScan(*r, static_cast<int64_t>(k) * kStepNs);
      // The map's frame is that of the first scan in the log: east's, whatever the two
      // connections' timing (west's would put the whole map, east included, 0.64 m off).
      if (k == 0 && r == &a) {
        ASSERT_TRUE(r->client->waitAllAcked(std::chrono::seconds(30)));
      }
    }
  }
  for (SimRobot* r : {&a, &b}) ASSERT_TRUE(r->client->waitAllAcked(std::chrono::seconds(180)));
  std::printf("[ stream ] %zu scans per robot acknowledged in %.1f s\n", tour.size(),
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());

  // The loop closures, and at least one between the two robots.
  client::HttpClient http(rmapd->httpUrl());
  nlohmann::json closures;
  // A cross-robot geometric closure (the one the correction rests on).
  const auto isCross = [](const nlohmann::json& c) {
    return c["source"] == "geometry" && c["query"]["robot_id"] != c["match"]["robot_id"];
  };
  for (int attempt = 0; attempt < 50; ++attempt) {  // closures are stored behind the acks
    closures = getJson(http, "/v1/loop-closures?map=shared&limit=100000").at("loop_closures");
    if (std::any_of(closures.begin(), closures.end(), isCross)) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  std::map<std::string, int> by_source, far_apart;  // far apart: the two places > 8 m from each other
  // A false place recognition: the two places truly more than half a reflectivity patch (8 m
  // wide) apart. (A geometric closure relates a scan to a submap's anchor, which may lie farther.)
  int judged = 0, wrong = 0;
  const auto truthOf = [&](const nlohmann::json& end) -> std::optional<Eigen::Vector3d> {
    const SimRobot& r = end["robot_id"] == a.id ? a : b;
    const auto t = r.truth.find(end["stamp_ns"].get<int64_t>());
    return t == r.truth.end() ? std::nullopt : std::optional(t->second);
  };
  // Measured relative poses against the truth's: geometry closures carry the scan-to-submap match.
  std::map<std::string, int> measured;
  double worst_m = 0.0, worst_rad = 0.0;
  const nlohmann::json* cross = nullptr;
  for (const nlohmann::json& c : closures) {
    const std::string source = c["source"];
    ++by_source[source];
    if (source == "geometry") {
      EXPECT_TRUE(c["relative_pose"].is_object()) << c;
      const nlohmann::json& along = c.at("ambiguous_direction");  // a unit planar vector, or null
      if (!along.is_null()) {
        EXPECT_NEAR(std::hypot(along[0].get<double>(), along[1].get<double>()), 1.0, 1e-9) << c;
        EXPECT_EQ(along[2].get<double>(), 0.0) << c;
      }
    } else {
      EXPECT_TRUE(c["ambiguous_direction"].is_null()) << c;
    }
    if (c["relative_pose"].is_object()) {
      if (const auto q = truthOf(c["query"]), m = truthOf(c["match"]); q && m) {
        ++measured[source];
        const auto [error_m, error_rad] = relativePoseError(c["relative_pose"], *q, *m);
        EXPECT_LT(error_m, 0.3) << c;
        EXPECT_LT(error_rad, 5.0 * M_PI / 180.0) << c;
        worst_m = std::max(worst_m, error_m);
        worst_rad = std::max(worst_rad, error_rad);
      }
    }
    if (source == "laser_intensity") {
      if (const auto q = truthOf(c["query"]), m = truthOf(c["match"]); q && m) {
        ++judged;
        const double apart_m = (*q - *m).head<2>().norm();
        if (apart_m > 4.0) {
          ++wrong;
          std::printf("[ false place recognition ] %.1f m apart: %s\n", apart_m, c.dump().c_str());
        }
      }
    }
    EXPECT_TRUE(source == "camera" || source == "laser_intensity" || source == "geometry") << c;
    EXPECT_EQ(c["map"], "shared");
    if (c["query"]["position"].is_array() && c["match"]["position"].is_array()) {
      const Eigen::Vector3d q = planarOf(c["query"]["position"], c["query"]["orientation"]);
      const Eigen::Vector3d m = planarOf(c["match"]["position"], c["match"]["orientation"]);
      far_apart[source] += (q - m).head<2>().norm() > 8.0;
    }
    if (!cross && isCross(c)) cross = &c;
  }
  std::printf("[ closures ] %zu: geometry %d (%d far apart), laser_intensity %d (%d far apart; %d judged by the "
              "truth, %d false)\n",
              closures.size(), by_source["geometry"], far_apart["geometry"], by_source["laser_intensity"],
              far_apart["laser_intensity"], judged, wrong);
  std::printf("[ relative poses ] judged by the truth: geometry %d, laser_intensity %d; worst %.3f m, %.2f°; %.0f "
              "matches refused for contradicting the poses\n",
              measured["geometry"], measured["laser_intensity"], worst_m, worst_rad * 180.0 / M_PI,
              metricValue(http.get("/metrics").body, "rmap_loop_closures_refused_total"));
  EXPECT_GT(measured["geometry"], 0);
  EXPECT_EQ(far_apart["geometry"], 0);
  EXPECT_EQ(wrong, 0);
  ASSERT_NE(cross, nullptr) << closures.dump();
  const nlohmann::json& c = *cross;
  for (const char* end : {"query", "match"}) {
    const std::string robot = c[end]["robot_id"];
    EXPECT_TRUE(robot == "east" || robot == "west") << c;
    ASSERT_TRUE(c[end]["position"].is_array()) << c;
    ASSERT_EQ(c[end]["position"].size(), 3u);
    ASSERT_EQ(c[end]["orientation"].size(), 4u);
  }
  EXPECT_GT(c["query"]["stamp_ns"].get<int64_t>(), c["match"]["stamp_ns"].get<int64_t>() - 1);
  EXPECT_GT(c["score"].get<double>(), 0.0);
  // Both places are the same place: the two poses lie close together in the map.
  const Eigen::Vector3d q = planarOf(c["query"]["position"], c["query"]["orientation"]);
  const Eigen::Vector3d m = planarOf(c["match"]["position"], c["match"]["orientation"]);
  EXPECT_LT((q - m).head<2>().norm(), 8.0) << c;
  // Both robots' filters find it; another robot's filter does not.
  for (const std::string robot : {"east", "west"}) {
    bool found = false;
    const nlohmann::json of_robot = getJson(http, "/v1/loop-closures?robot=" + robot);
    for (const nlohmann::json& e : of_robot.at("loop_closures")) {
      found = found || e["id"] == c["id"];
      EXPECT_TRUE(e["query"]["robot_id"] == robot || e["match"]["robot_id"] == robot) << e;
    }
    EXPECT_TRUE(found) << robot;
  }

  // The same closure was pushed on the viewer stream.
  watching = false;
  watcher.join();
  bool seen = false;
  for (const nlohmann::json& p : pushed) seen = seen || (p["id"] == c["id"] && p["source"] == c["source"]);
  EXPECT_TRUE(seen) << "pushed " << pushed.size() << " loop closures";

  // The corrected trajectories (served by the API) are closer to the truth than the live estimates.
  const std::string metrics = http.get("/metrics").body;
  EXPECT_GT(metricValue(metrics, "rmap_trajectory_corrections_total"), 0.0);
  std::this_thread::sleep_for(std::chrono::milliseconds(700));  // trajectory poses are written every 0.5 s
  double live_sum = 0.0, corrected_sum = 0.0;
  for (SimRobot* r : {&a, &b}) {
    std::map<int64_t, Eigen::Vector3d> corrected;
    const nlohmann::json trajectory = getJson(http, "/v1/robots/" + r->id + "/trajectory");
    for (const nlohmann::json& p : trajectory.at("poses")) {
      corrected[p["stamp_ns"].get<int64_t>()] = planarOf(p["position"], p["orientation"]);
    }
    size_t live_n = 0, corrected_n = 0;
    std::lock_guard lock(r->mutex);
    const double live = meanError(r->live_estimates, r->truth, &live_n);
    const double fixed = meanError(corrected, r->truth, &corrected_n);
    std::printf("[ %s ] mean error live %.3f m (%zu poses), corrected %.3f m (%zu poses)\n", r->id.c_str(), live,
                live_n, fixed, corrected_n);
    EXPECT_EQ(corrected_n, r->truth.size());
    live_sum += live;
    corrected_sum += fixed;
  }
  EXPECT_LT(corrected_sum, live_sum);

  // The 3D map's planar row at the laser height agrees with the corrected 2D map: its occupied
  // cells lie on 2D cells that are not free (no walls left at the poses before a correction).
  const client::HttpResponse yaml = http.get("/v1/maps/shared/grid2d.yaml");
  const client::HttpResponse pgm = http.get("/v1/maps/shared/grid2d.pgm");
  ASSERT_EQ(yaml.status, 200);
  ASSERT_EQ(pgm.status, 200);
  double r2 = 0, origin_x = 0, origin_y = 0;
  ASSERT_EQ(std::sscanf(yaml.body.c_str() + yaml.body.find("resolution: "), "resolution: %lf", &r2), 1);
  ASSERT_EQ(std::sscanf(yaml.body.c_str() + yaml.body.find("origin: "), "origin: [%lf, %lf", &origin_x, &origin_y), 2);
  int width = 0, height = 0, maxval = 0, header = 0;
  ASSERT_EQ(std::sscanf(pgm.body.c_str(), "P5\n%d %d\n%d\n%n", &width, &height, &maxval, &header), 3);
  const int i0 = static_cast<int>(std::lround(origin_x / r2)), j0 = static_cast<int>(std::lround(origin_y / r2));
  const auto free2d = [&](int i, int j) {  // map_server: 254 free, 0 occupied, 205 unknown
    const int col = i - i0, row = height - 1 - (j - j0);
    if (col < 0 || col >= width || row < 0 || row >= height) return false;
    return static_cast<uint8_t>(pgm.body[header + row * width + col]) == 254;
  };
  char box[200];
  std::snprintf(box, sizeof box, "/v1/maps/shared/occupancy/box?min=%f,%f,%f&max=%f,%f,%f&limit=100000", origin_x,
                origin_y, kCrossingLaserHeight_m + 0.01, origin_x + width * r2, origin_y + height * r2, kCrossingLaserHeight_m + 0.01);
  const nlohmann::json cuboids = getJson(http, box).at("cuboids");
  const double r3 = getJson(http, "/v1/maps/shared").at("resolution_m").get<double>();
  size_t occupied3d = 0, on_free = 0;
  for (const nlohmann::json& c : cuboids) {
    if (c["state"] != "occupied") continue;
    for (double x = c["min"][0].get<double>() + r3 / 2; x < c["max"][0].get<double>(); x += r3) {
      for (double y = c["min"][1].get<double>() + r3 / 2; y < c["max"][1].get<double>(); y += r3) {
        ++occupied3d;
        bool all_free = true;
        for (double dx : {-r3 / 4, r3 / 4}) {
          for (double dy : {-r3 / 4, r3 / 4}) {
            all_free = all_free && free2d(static_cast<int>(std::floor((x + dx) / r2)),
                                          static_cast<int>(std::floor((y + dy) / r2)));
          }
        }
        on_free += all_free;
      }
    }
  }
  std::printf("[ 3D row ] %zu occupied cells at the laser height, %zu of them on free 2D cells\n", occupied3d,
              on_free);
  EXPECT_GT(occupied3d, 100u);
  EXPECT_LT(static_cast<double>(on_free), 0.02 * static_cast<double>(occupied3d));

  // After kill -9 the stored closures are all there, and the replay of the log, which finds
  // them again, stores none twice.
  for (SimRobot* r : {&a, &b}) r->client->close();
  const nlohmann::json before = getJson(http, "/v1/loop-closures?limit=100000").at("loop_closures");
  rmapd->kill9();
  rmapd = std::make_unique<RmapdProcess>(dir.path() / "data");
  client::HttpClient again(rmapd->httpUrl());
  const nlohmann::json after = getJson(again, "/v1/loop-closures?limit=100000").at("loop_closures");
  std::set<std::tuple<std::string, std::string, int64_t, std::string, int64_t>> keys;
  std::set<int64_t> ids;
  for (const nlohmann::json& e : after) {
    ids.insert(e["id"].get<int64_t>());
    EXPECT_TRUE(keys.emplace(e["source"], e["query"]["robot_id"], e["query"]["stamp_ns"], e["match"]["robot_id"],
                             e["match"]["stamp_ns"])
                    .second)
        << "stored twice: " << e;
  }
  for (const nlohmann::json& e : before) EXPECT_TRUE(ids.count(e["id"].get<int64_t>())) << e;
  std::printf("[ restart ] %zu closures before kill -9, %zu after the replay\n", before.size(), after.size());
}

/// The laser-intensity closures of `map`, once their count holds: they are recognised behind the acks.
nlohmann::json settledLaserIntensityClosures(client::HttpClient& http, const std::string& map) {
  nlohmann::json closures;
  size_t before = SIZE_MAX;
  for (int attempt = 0; attempt < 60; ++attempt) {
    closures = getJson(http, "/v1/loop-closures?map=" + map + "&source=laser_intensity&limit=100000").at("loop_closures");
    if (closures.size() == before && !closures.empty()) break;
    before = closures.size();
    std::this_thread::sleep_for(std::chrono::seconds(2));
  }
  return closures;
}

// A 2D-laser robot drives its tour there, back and there again: rmapd recognises the places
// in the reflectivity patches of its map (turned 180° on the way back), and each patch
// closure's relative pose, measured by the 2D rigid fit of the two patches, agrees with the
// one between the true poses.
TEST(LoopClosure, ReflectivityPatchClosuresMeasureTheRobotsMotionBetweenThePatches) {
  TempDir dir("rmap-loop-patch");
  RmapdProcess rmapd(dir.path() / "data");
  const LaserWorld scene = laserWorld(150);
  const std::vector<Eigen::Isometry3d>& there = scene.tour;
  const std::vector<Eigen::Isometry3d> back = reversedTour(there);
  std::vector<Eigen::Isometry3d> tour = there;
  tour.insert(tour.end(), back.begin(), back.end());
  tour.insert(tour.end(), there.begin(), there.end());
  const client::Laser2dRobotOptions laser = sickLaser();
  SimRobot robot{"solo", client::Laser2dRobot(scene.world, tour, laser, 21), {0, 0, 0}, nullptr, {}, {}, {}};
  connect(robot, rmapd.wsUrl(), "patches");
  for (size_t k = 0; k < tour.size(); ++k) {
    sendNextScan(robot, static_cast<int64_t>(k) * kStepNs);
#ifdef RMAP_SANITIZE
    // Live, rmapd drops patches that find place recognition behind: the sanitized build,
    // several times slower, gets them recognised at a slower feed.
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
#endif
  }
  ASSERT_TRUE(robot.client->waitAllAcked(std::chrono::seconds(180)));

  client::HttpClient http(rmapd.httpUrl());
  const nlohmann::json closures = settledLaserIntensityClosures(http, "patches");
  ASSERT_GE(closures.size(), 10u);
  double worst_m = 0.0, worst_rad = 0.0;
  for (const nlohmann::json& c : closures) {
    ASSERT_TRUE(c["relative_pose"].is_object()) << c;
    const auto q = robot.truth.find(c["query"]["stamp_ns"].get<int64_t>());
    const auto m = robot.truth.find(c["match"]["stamp_ns"].get<int64_t>());
    ASSERT_TRUE(q != robot.truth.end() && m != robot.truth.end()) << c;
    const auto [error_m, error_rad] = relativePoseError(c["relative_pose"], q->second, m->second);
    EXPECT_LT(error_m, 0.3) << c;
    EXPECT_LT(error_rad, 5.0 * M_PI / 180.0) << c;
    worst_m = std::max(worst_m, error_m);
    worst_rad = std::max(worst_rad, error_rad);
  }
  const std::string metrics = http.get("/metrics").body;
  std::printf(
      "[ patches ] %zu closures; measured relative pose vs truth: worst %.3f m, %.2f°; %.0f refused, %.0f frames "
      "dropped\n",
      closures.size(), worst_m, worst_rad * 180.0 / M_PI, metricValue(metrics, "rmap_loop_closures_refused_total"),
      metricValue(metrics, "rmap_loop_frames_dropped_total"));
}

/// A pose from the API's {position [x,y,z], orientation [w,x,y,z]}.
Eigen::Isometry3d poseOf(const nlohmann::json& pose) {
  const nlohmann::json &p = pose.at("position"), &q = pose.at("orientation");
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.translation() = Eigen::Vector3d(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
  out.linear() = Eigen::Quaterniond(q[0].get<double>(), q[1].get<double>(), q[2].get<double>(), q[3].get<double>())
                     .normalized()
                     .toRotationMatrix();
  return out;
}

// Two simulated lidar robots drive their tours twice: rmapd recognises the second laps in the
// intensity panoramas of their clouds, and each closure's relative pose, measured by the 3D
// rigid fit, agrees with the one between the true sensor poses the robots sent.
TEST(LoopClosure, LidarPanoramaClosuresMeasureTheirRelativePoseInMetres) {
  TempDir dir("rmap-loop-lidar");
  RmapdProcess rmapd(dir.path() / "data");
  const client::SimScene scene = client::makeSimScene(3);
  client::SimFeedOptions feed;
  feed.server_url = rmapd.wsUrl();
  feed.robots = 2;
  feed.map_prefix = "lidar";
  feed.poses = 120;  // 36 m: about 60 panoramas a lap, more than the detector's window of 50
  feed.max_clouds = 240;
  // Live, rmapd drops panoramas that find place recognition behind: the sanitized build,
  // several times slower, gets the same frames recognised at a slower feed.
#ifdef RMAP_SANITIZE
  feed.rate_hz = 5.0;
#else
  feed.rate_hz = 20.0;
#endif
  feed.duration = std::chrono::seconds(600);
  feed.timeout = std::chrono::seconds(60);
  const client::SimFeedResult sent = client::runSimFeed(scene, feed);
  ASSERT_TRUE(sent.errors.empty()) << sent.errors.front();
  ASSERT_EQ(sent.clouds_acked, 480u);

  client::HttpClient http(rmapd.httpUrl());
  const nlohmann::json closures = settledLaserIntensityClosures(http, "lidar");
  ASSERT_GE(closures.size(), 10u);
  int cross = 0;
  double worst_m = 0.0, worst_deg = 0.0;
  for (const nlohmann::json& c : closures) {
    ASSERT_TRUE(c["relative_pose"].is_object()) << c;
    // The robots sent their true sensor poses: the truth of the closure is the one between them.
    const Eigen::Isometry3d query = poseOf(c["query"]), match = poseOf(c["match"]);
    const Eigen::Isometry3d error = (match.inverse() * query).inverse() * poseOf(c["relative_pose"]);
    const double error_m = error.translation().norm();
    const double error_deg = Eigen::AngleAxisd(error.linear()).angle() * 180.0 / M_PI;
    EXPECT_LT((query.translation() - match.translation()).norm(), 3.0) << c;
    // The worst are tilts: the 16 rings are 2° apart, and a keypoint between two lifts to one of them.
    EXPECT_LT(error_m, 0.3) << c;
    EXPECT_LT(error_deg, 5.0) << c;
    worst_m = std::max(worst_m, error_m);
    worst_deg = std::max(worst_deg, error_deg);
    cross += c["query"]["robot_id"] != c["match"]["robot_id"];
  }
  const double dropped = metricValue(http.get("/metrics").body, "rmap_loop_frames_dropped_total");
  std::printf(
      "[ panoramas ] %zu closures (%d across robots, %.0f frames dropped); measured relative pose vs truth: worst "
      "%.3f m, %.2f°\n",
      closures.size(), cross, dropped, worst_m, worst_deg);
}

TEST(LoopClosure, BadQueriesOfTheEndpointGetJsonErrors) {
  TempDir dir("rmap-loop-bad");
  RmapdProcess rmapd(dir.path() / "data");
  client::HttpClient http(rmapd.httpUrl());
  for (const auto& [target, status] : std::vector<std::pair<std::string, int>>{
           {"/v1/loop-closures?source=sonar", 400},
           {"/v1/loop-closures?limit=0", 400},
           {"/v1/loop-closures?since=-5", 400},
           {"/v1/loop-closures?since=1e3", 400},
           {"/v1/loop-closures?robot=no%2Fslash", 400},
           {"/v1/loop-closures?maps=x", 400},
           {"/v1/loop-closures?map=nowhere", 404},
           {"/v1/loop-closures?robot=nobody", 404}}) {
    const nlohmann::json body = getJson(http, target, status);
    EXPECT_TRUE(body["error"]["code"].is_string()) << target << ": " << body;
    EXPECT_FALSE(body["error"]["message"].get<std::string>().empty()) << target;
  }
  EXPECT_EQ(getJson(http, "/v1/loop-closures").at("loop_closures"), nlohmann::json::array());
}

}  // namespace
}  // namespace rmap::testing
