#include "client/sim_feed.h"

#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <cmath>
#include <map>

#include "fake_robot_server.h"

namespace rmap::client {
namespace {

using std::chrono::milliseconds;
using test::FakeRobotServer;
using test::FakeRobotServerOptions;

/// One scene for the whole suite (building it is cheap, but there is no need to repeat it).
const SimScene& scene() {
  static const SimScene s = makeSimScene(3);
  return s;
}

/// A small, fast feed against `server`.
SimFeedOptions smallFeed(const FakeRobotServer& server) {
  SimFeedOptions o;
  o.server_url = server.url();
  o.rate_hz = 0.0;
  o.duration = std::chrono::seconds(20);
  o.poses = 20;
  o.lidar_rings = 8;
  o.lidar_columns = 90;
  o.timeout = milliseconds(5000);
  return o;
}

bool sameBoxes(const std::vector<Eigen::AlignedBox3d>& a, const std::vector<Eigen::AlignedBox3d>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!a[i].min().isApprox(b[i].min()) || !a[i].max().isApprox(b[i].max())) return false;
  }
  return true;
}

TEST(SimFeed, SceneIsDeterministicInItsSeed) {
  const SimScene a = makeSimScene(5, 0.1);
  const SimScene b = makeSimScene(5, 0.1);
  const SimScene c = makeSimScene(6, 0.1);
  EXPECT_DOUBLE_EQ(a.world.voxelSize(), 0.1);
  EXPECT_GT(a.world.occupiedCount(), 0u);
  EXPECT_EQ(a.world.occupiedCount(), b.world.occupiedCount());
  EXPECT_TRUE(sameBoxes(a.layout.rooms, b.layout.rooms));
  EXPECT_TRUE(sameBoxes(a.layout.furniture, b.layout.furniture));
  EXPECT_FALSE(sameBoxes(a.layout.furniture, c.layout.furniture));
  EXPECT_FALSE(a.layout.stair_flights.empty());  // two storeys to drive through
}

TEST(SimFeed, RobotsStreamLidarCloudsOfTheBuilding) {
  FakeRobotServer server;
  SimFeedOptions o = smallFeed(server);
  o.robots = 2;
  o.max_clouds = 3;
  o.map_prefix = "floor";
  o.shared_map = false;
  o.robot_prefix = "bot";
  o.resolution_m = 0.05;
  const SimFeedResult result = runSimFeed(scene(), o);

  EXPECT_TRUE(result.errors.empty()) << result.errors.front();
  EXPECT_EQ(result.clouds_sent, 6u);
  EXPECT_EQ(result.clouds_acked, 6u);
  EXPECT_EQ(result.ack_latencies_ms.size(), 6u);
  for (const double ms : result.ack_latencies_ms) {
    EXPECT_GE(ms, 0.0);
    EXPECT_LE(ms, result.wall_s * 1000.0);
  }

  std::map<std::string, std::string> map_of;
  for (const v1::Hello& hello : server.hellos()) {
    map_of[hello.robot_id()] = hello.map();
    EXPECT_DOUBLE_EQ(hello.resolution_m(), 0.05);
    ASSERT_EQ(hello.sensors_size(), 1);
    EXPECT_EQ(hello.sensors(0).name(), "lidar");
    EXPECT_EQ(hello.sensors(0).kind(), v1::SensorDescription::LIDAR_3D);
    EXPECT_EQ(hello.sensors(0).model(), "sim-lidar-16");
  }
  EXPECT_EQ(map_of, (std::map<std::string, std::string>{{"bot-0", "floor-0"}, {"bot-1", "floor-1"}}));

  // Points are world-frame returns off the building's surfaces (0.01 m range noise).
  const Eigen::AlignedBox3d bounds = scene().world.bounds();
  const Eigen::AlignedBox3d near_bounds(bounds.min() - Eigen::Vector3d::Constant(0.1),
                                       bounds.max() + Eigen::Vector3d::Constant(0.1));
  const auto messages = server.messages();
  ASSERT_EQ(messages.size(), 6u);
  uint64_t points_total = 0;
  std::map<uint64_t, int> seq_count;
  for (const v1::RobotMessage& m : messages) {
    ++seq_count[m.seq()];
    ASSERT_TRUE(m.has_cloud());
    const v1::PointCloud& c = m.cloud();
    EXPECT_EQ(c.sensor(), "lidar");
    EXPECT_EQ(c.frame(), v1::PointCloud::MAP);
    EXPECT_GT(c.stamp_ns(), 0);
    const v1::Vector3& p = c.sensor_pose().position_m();
    const Eigen::Vector3d origin(p.x(), p.y(), p.z());
    EXPECT_TRUE(bounds.contains(origin));
    EXPECT_FALSE(scene().world.occupied(origin));
    const v1::Quaternion& q = c.sensor_pose().orientation();
    EXPECT_NEAR(q.w() * q.w() + q.x() * q.x() + q.y() * q.y() + q.z() * q.z(), 1.0, 1e-9);
    ASSERT_EQ(c.xyz_m_size() % 3, 0);
    const int points = c.xyz_m_size() / 3;
    EXPECT_GT(points, 8 * 90 / 2);  // indoors nearly every beam hits something within 20 m
    EXPECT_EQ(c.intensities_size(), points);
    points_total += static_cast<uint64_t>(points);
    for (int i = 0; i < points; ++i) {
      const Eigen::Vector3d x(c.xyz_m(3 * i), c.xyz_m(3 * i + 1), c.xyz_m(3 * i + 2));
      ASSERT_TRUE(x.allFinite());
      ASSERT_TRUE(near_bounds.contains(x)) << x.transpose();
      ASSERT_LE((x - origin).norm(), 20.1);
      ASSERT_TRUE(std::isfinite(c.intensities(i)) && c.intensities(i) >= 0.0f);
    }
  }
  EXPECT_EQ(result.points_sent, points_total);
  // Each robot numbers its own stream 1, 2, 3.
  EXPECT_EQ(seq_count, (std::map<uint64_t, int>{{1, 2}, {2, 2}, {3, 2}}));
}

TEST(SimFeed, SharedMapRateAndPrecomputedCycle) {
  FakeRobotServer server;
  SimFeedOptions o = smallFeed(server);
  o.robots = 1;
  o.max_clouds = 5;
  o.rate_hz = 20.0;
  o.precompute_clouds = 2;
  const SimFeedResult result = runSimFeed(scene(), o);

  EXPECT_TRUE(result.errors.empty()) << result.errors.front();
  EXPECT_EQ(result.clouds_acked, 5u);
  EXPECT_GE(result.wall_s, 4 * 0.05 - 0.01);  // five clouds at 20 Hz span four periods
  ASSERT_EQ(server.hellos().size(), 1u);
  EXPECT_EQ(server.hellos()[0].robot_id(), "sim-robot-0");
  EXPECT_EQ(server.hellos()[0].map(), "sim");
  const auto m = server.messages();
  ASSERT_EQ(m.size(), 5u);
  // Clouds cycle 0, 1, 0, 1, 0 with fresh stamps.
  EXPECT_EQ(m[2].cloud().xyz_m_size(), m[0].cloud().xyz_m_size());
  EXPECT_TRUE(std::equal(m[2].cloud().xyz_m().begin(), m[2].cloud().xyz_m().end(), m[0].cloud().xyz_m().begin()));
  EXPECT_TRUE(std::equal(m[3].cloud().xyz_m().begin(), m[3].cloud().xyz_m().end(), m[1].cloud().xyz_m().begin()));
  EXPECT_NE(m[0].cloud().sensor_pose().position_m().x(), m[1].cloud().sensor_pose().position_m().x());
  EXPECT_GT(m[2].cloud().stamp_ns(), m[0].cloud().stamp_ns());
}

TEST(SimFeed, DurationStopsTheFeedAndProgressIsReported) {
  FakeRobotServer server;
  SimFeedOptions o = smallFeed(server);
  o.robots = 2;
  o.rate_hz = 10.0;
  o.duration = milliseconds(1300);
  std::vector<SimFeedProgress> progress;
  o.on_progress = [&progress](const SimFeedProgress& p) { progress.push_back(p); };
  const SimFeedResult result = runSimFeed(scene(), o);

  EXPECT_TRUE(result.errors.empty()) << result.errors.front();
  // At 10 Hz for 1.3 s at most 14 clouds per robot; fewer when planning the
  // tour ate into the time (slow or sanitised builds).
  EXPECT_GE(result.clouds_sent, 2u);
  EXPECT_LE(result.clouds_sent, 2u * 14);
  EXPECT_EQ(result.clouds_acked, result.clouds_sent);
  EXPECT_LT(result.wall_s, 3.0);
  ASSERT_GE(progress.size(), 1u);
  EXPECT_GE(progress[0].elapsed_s, 0.9);
  for (const SimFeedProgress& p : progress) {
    EXPECT_LE(p.clouds_acked, p.clouds_sent);
    EXPECT_LE(p.clouds_sent, result.clouds_sent);
    EXPECT_LE(p.points_acked, result.points_sent);
    EXPECT_EQ(p.points_acked > 0, p.clouds_acked > 0);  // acked clouds carry their points
  }
}

TEST(SimFeed, LaserRobotsSendScansWithOdometryAndScoreTheirPoses) {
  // The fake answers each scan with its odometry as the "estimate": the
  // reported error is then the odometry's drift from the truth.
  FakeRobotServerOptions with_poses;
  with_poses.poses = true;
  FakeRobotServer server(with_poses);
  SimFeedOptions o = smallFeed(server);
  o.robots = 1;
  o.laser2d_robots = 1;
  o.laser2d_model = sim::Laser2dModel::hokuyoLike();
  o.max_clouds = 6;
  const SimFeedResult result = runSimFeed(scene(), o);

  EXPECT_TRUE(result.errors.empty()) << result.errors.front();
  EXPECT_EQ(result.clouds_sent, 6u);
  EXPECT_EQ(result.clouds_acked, 6u);
  EXPECT_EQ(result.scans_sent, 6u);
  EXPECT_EQ(result.scans_acked, 6u);
  EXPECT_EQ(result.pose_estimates, 6u);
  EXPECT_GT(result.pose_error_max_m, 0.0);  // five noisy steps after an exact start
  EXPECT_LT(result.pose_error_max_m, 0.3);  // 5 % of at most 1.25 m, plus heading drift
  EXPECT_GT(result.pose_error_mean_m, 0.0);
  EXPECT_LT(result.pose_error_mean_m, result.pose_error_max_m);
  EXPECT_GT(result.heading_error_max_rad, 0.0);

  std::map<std::string, v1::Hello> hello_of;
  for (const v1::Hello& hello : server.hellos()) hello_of[hello.robot_id()] = hello;
  ASSERT_EQ(hello_of.size(), 2u);
  EXPECT_EQ(hello_of.at("sim-robot-0").sensors(0).kind(), v1::SensorDescription::LIDAR_3D);
  const v1::Hello& laser_hello = hello_of.at("sim-robot-1");
  EXPECT_EQ(laser_hello.map(), "sim");
  ASSERT_EQ(laser_hello.sensors_size(), 1);
  const v1::SensorDescription& laser = laser_hello.sensors(0);
  EXPECT_EQ(laser.kind(), v1::SensorDescription::LASER_2D);
  EXPECT_EQ(laser.model(), "hokuyo_like");
  EXPECT_DOUBLE_EQ(laser.mount().position_m().x(), 0.15);
  EXPECT_DOUBLE_EQ(laser.mount().position_m().z(), 1.0);

  std::vector<v1::LaserScan2D> scans;
  for (const v1::RobotMessage& m : server.messages()) {
    if (m.has_scan()) scans.push_back(m.scan());
  }
  ASSERT_EQ(scans.size(), 6u);
  const Eigen::AlignedBox3d bounds = scene().world.bounds();
  for (size_t k = 0; k < scans.size(); ++k) {
    const v1::LaserScan2D& s = scans[k];
    EXPECT_EQ(s.sensor(), laser.name());
    EXPECT_GT(s.stamp_ns(), 0);
    if (k > 0) {
      EXPECT_GT(s.stamp_ns(), scans[k - 1].stamp_ns());
    }
    ASSERT_EQ(s.ranges_m_size(), 1081);  // the Hokuyo preset
    ASSERT_EQ(s.intensities_size(), s.ranges_m_size());
    EXPECT_NEAR(s.angle_min_rad() + 1080 * s.angle_increment_rad(), -s.angle_min_rad(), 1e-4);
    int returns = 0;
    for (int i = 0; i < s.ranges_m_size(); ++i) {
      const float r = s.ranges_m(i);
      ASSERT_FALSE(std::isnan(r));
      ASSERT_FALSE(r < 0.0f && std::isinf(r));  // no −inf on the wire
      if (std::isfinite(r) && r <= s.range_max_m()) {
        ++returns;
        EXPECT_GE(s.intensities(i), 0.0f);
      }
    }
    EXPECT_GT(returns, 1081 / 2);  // indoors most beams hit a wall
    // Odometry: on the ground storey, inside the building, moving by about one step.
    ASSERT_TRUE(s.has_odometry());
    const Eigen::Vector3d base(s.odometry().x_m(), s.odometry().y_m(), 0.5);
    EXPECT_TRUE(bounds.contains(base)) << base.transpose();
    if (k > 0) {
      const Eigen::Vector2d step(s.odometry().x_m() - scans[k - 1].odometry().x_m(),
                                 s.odometry().y_m() - scans[k - 1].odometry().y_m());
      EXPECT_LT(step.norm(), 0.4);
    }
  }

  // Deterministic in the seed: a second run sends the same scans.
  FakeRobotServer again_server(with_poses);
  SimFeedOptions again = o;
  again.server_url = again_server.url();
  const SimFeedResult again_result = runSimFeed(scene(), again);
  EXPECT_DOUBLE_EQ(again_result.pose_error_max_m, result.pose_error_max_m);
  std::vector<v1::LaserScan2D> again_scans;
  for (const v1::RobotMessage& m : again_server.messages()) {
    if (m.has_scan()) again_scans.push_back(m.scan());
  }
  ASSERT_EQ(again_scans.size(), scans.size());
  for (size_t k = 0; k < scans.size(); ++k) {
    EXPECT_EQ(again_scans[k].odometry().SerializeAsString(), scans[k].odometry().SerializeAsString());
    EXPECT_TRUE(std::equal(scans[k].ranges_m().begin(), scans[k].ranges_m().end(), again_scans[k].ranges_m().begin()));
  }

  // A robot the server already holds 4 messages of resumes at its fifth step.
  FakeRobotServerOptions holding = with_poses;
  holding.last_durable_seq = 4;
  FakeRobotServer resume_server(holding);
  SimFeedOptions resume = o;
  resume.server_url = resume_server.url();
  resume.max_clouds = 2;
  EXPECT_TRUE(runSimFeed(scene(), resume).errors.empty());
  std::vector<v1::RobotMessage> resumed;
  for (const v1::RobotMessage& m : resume_server.messages()) {
    if (m.has_scan()) resumed.push_back(m);
  }
  ASSERT_EQ(resumed.size(), 2u);
  for (size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(resumed[k].seq(), 5 + k);
    EXPECT_EQ(resumed[k].scan().odometry().SerializeAsString(), scans[4 + k].odometry().SerializeAsString()) << k;
  }
}

TEST(SimFeed, LaserRobotsAloneNeedNoLidarRobot) {
  FakeRobotServer server;
  SimFeedOptions o = smallFeed(server);
  o.robots = 0;
  o.laser2d_robots = 2;
  o.shared_map = false;
  o.max_clouds = 2;
  const SimFeedResult result = runSimFeed(scene(), o);
  EXPECT_TRUE(result.errors.empty()) << result.errors.front();
  EXPECT_EQ(result.clouds_sent, 0u);
  EXPECT_EQ(result.scans_acked, 4u);
  EXPECT_EQ(result.pose_estimates, 0u);  // this fake sends none
  std::map<std::string, std::string> map_of;
  for (const v1::Hello& hello : server.hellos()) {
    map_of[hello.robot_id()] = hello.map();
    EXPECT_EQ(hello.sensors(0).model(), "sick_like");
  }
  EXPECT_EQ(map_of, (std::map<std::string, std::string>{{"sim-robot-0", "sim-0"}, {"sim-robot-1", "sim-1"}}));
}

TEST(SimFeed, ConnectionFailuresAreReportedNotThrown) {
  uint16_t port = 0;
  {  // a port nobody listens on any more
    boost::asio::io_context ioc;
    boost::asio::ip::tcp::acceptor acceptor(ioc, {boost::asio::ip::make_address("127.0.0.1"), 0});
    port = acceptor.local_endpoint().port();
  }
  SimFeedOptions o;
  o.server_url = "ws://127.0.0.1:" + std::to_string(port);
  o.robots = 2;
  o.poses = 5;
  o.max_clouds = 1;
  o.timeout = milliseconds(2000);
  const SimFeedResult result = runSimFeed(scene(), o);
  EXPECT_EQ(result.clouds_sent, 0u);
  ASSERT_EQ(result.errors.size(), 2u);
  for (const std::string robot : {"sim-robot-0", "sim-robot-1"}) {
    EXPECT_TRUE(std::any_of(result.errors.begin(), result.errors.end(),
                            [&](const std::string& e) { return e.rfind(robot + ": ", 0) == 0; }))
        << robot;
  }
}

TEST(SimFeed, RejectsBadOptions) {
  SimFeedOptions o;
  o.robots = 0;
  EXPECT_THROW(runSimFeed(scene(), o), std::invalid_argument);  // no robot at all
  o.laser2d_robots = -1;
  EXPECT_THROW(runSimFeed(scene(), o), std::invalid_argument);
  o.laser2d_robots = 1;
  o.laser2d_model.beams = 1;
  EXPECT_THROW(runSimFeed(scene(), o), std::invalid_argument);
  o.laser2d_model = sim::Laser2dModel::sickLike();
  o.laser2d_robots = 0;
  o.robots = 1;
  o.rate_hz = -1.0;
  EXPECT_THROW(runSimFeed(scene(), o), std::invalid_argument);
  o.rate_hz = 1.0;
  o.lidar_rings = 0;
  EXPECT_THROW(runSimFeed(scene(), o), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::client
