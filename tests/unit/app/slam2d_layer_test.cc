// The 2D SLAM of a map as a robot session drives it: estimates before acks, the robot's pose,
// the planar cloud in the 3D map, refused scans, and the same state after a restart.
#include "app/slam2d_layer.h"

#include <gtest/gtest.h>

#include <cmath>

#include "app/robot_session.h"
#include "service_test_support.h"

namespace rmap::app {
namespace {

using testing::RecordingConnection;

constexpr double kMountX_m = 0.2;
constexpr double kMountZ_m = 0.3;

/// A scan from a laser at (kMountX_m, 0) facing +x inside the room [-4, 4] × [-3, 3] m.
v1::RobotMessage roomScan(uint64_t seq, bool with_returns = true) {
  v1::RobotMessage m;
  m.set_seq(seq);
  v1::LaserScan2D& scan = *m.mutable_scan();
  scan.set_sensor("front");
  scan.set_stamp_ns(static_cast<int64_t>(seq) * 100'000'000);
  constexpr int kBeams = 360;
  scan.set_angle_min_rad(static_cast<float>(-M_PI));
  scan.set_angle_increment_rad(static_cast<float>(2 * M_PI / kBeams));
  scan.set_range_min_m(0.05f);
  scan.set_range_max_m(20.0f);
  for (int i = 0; i < kBeams; ++i) {
    const double a = -M_PI + i * 2 * M_PI / kBeams, c = std::cos(a), s = std::sin(a);
    const double tx = c > 0 ? (4 - kMountX_m) / c : c < 0 ? (-4 - kMountX_m) / c : INFINITY;
    const double ty = s > 0 ? 3 / s : s < 0 ? -3 / s : INFINITY;
    scan.add_ranges_m(with_returns ? static_cast<float>(std::min(tx, ty)) : INFINITY);
    scan.add_intensities(300.0f);
  }
  scan.mutable_odometry();  // the robot stands at the odometry origin
  return m;
}

class Slam2dLayerTest : public ::testing::Test {
 protected:
  void SetUp() override { connect(); }
  void TearDown() override { session_->onClose(); }
  void connect() {
    connection_ = std::make_shared<RecordingConnection>();
    session_ = std::make_shared<RobotSession>(*service_, Principal{Role::kAdmin, {}});
    session_->onOpen(connection_);
    v1::RobotMessage hello;
    hello.mutable_hello()->set_robot_id("bot");
    hello.mutable_hello()->set_map("lab");
    v1::SensorDescription& laser = *hello.mutable_hello()->add_sensors();
    laser.set_name("front");
    laser.set_kind(v1::SensorDescription::LASER_2D);
    laser.set_model("room-laser");
    laser.mutable_mount()->mutable_position_m()->set_x(kMountX_m);
    laser.mutable_mount()->mutable_position_m()->set_z(kMountZ_m);
    session_->onMessage(hello.SerializeAsString(), true);
    ASSERT_TRUE(connection_->waitFor(1)[0].has_welcome());
  }
  void send(const v1::RobotMessage& message) { session_->onMessage(message.SerializeAsString(), true); }

  store::TempDir dir_;
  std::unique_ptr<MappingService> service_ = std::make_unique<MappingService>(testing::configIn(dir_.path()));
  std::shared_ptr<RecordingConnection> connection_;
  std::shared_ptr<RobotSession> session_;
};

TEST_F(Slam2dLayerTest, EachScanGetsItsEstimateBeforeItsAck) {
  for (uint64_t seq = 1; seq <= 3; ++seq) send(roomScan(seq));
  const std::vector<v1::ServerMessage> sent = connection_->waitFor(7);
  ASSERT_EQ(sent.size(), 7u);
  for (uint64_t seq = 1; seq <= 3; ++seq) {
    const v1::ServerMessage& pose = sent[2 * seq - 1];
    const v1::ServerMessage& ack = sent[2 * seq];
    ASSERT_TRUE(pose.has_pose()) << pose.DebugString();
    EXPECT_EQ(pose.pose().seq(), seq);
    EXPECT_EQ(pose.pose().stamp_ns(), static_cast<int64_t>(seq) * 100'000'000);
    // The base, not the laser: the mount's 0.2 m are taken off.
    EXPECT_NEAR(pose.pose().pose().position_m().x(), 0.0, 0.03);
    EXPECT_NEAR(pose.pose().pose().position_m().y(), 0.0, 0.03);
    EXPECT_EQ(pose.pose().pose().position_m().z(), 0.0);
    ASSERT_TRUE(ack.has_ack());
    EXPECT_EQ(ack.ack().seq(), seq);
  }
  const std::shared_ptr<MapWorker> map = service_->findMap("lab");
  EXPECT_TRUE(map->slam2d().hasLayer());
  EXPECT_EQ(map->slam2d().scans(), 3u);
  EXPECT_EQ(service_->metrics().slam2d_scans.load(), 3u);
  EXPECT_EQ(service_->metrics().pose_estimates_sent.load(), 3u);
  // The robot's pose, and the east wall in the 3D map at the laser's height.
  const std::optional<RobotStatus> robot = service_->robot("bot");
  ASSERT_TRUE(robot && robot->last_pose);
  EXPECT_NEAR(robot->last_pose->pose.translation().x(), 0.0, 0.03);
  EXPECT_EQ(map->map().query({4.02, 0.05, kMountZ_m + 0.01}).state, map3d::CellState::kOccupied);
  EXPECT_EQ(map->map().query({2.0, 0.05, kMountZ_m + 0.01}).state, map3d::CellState::kFree);
  EXPECT_EQ(map->map().query({4.02, 0.05, kMountZ_m + 0.5}).state, map3d::CellState::kUnknown);
  // The grid: the wall occupied, the floor free.
  map->slam2d().read([](const Grid2dSource& grid) {
    const double r = grid.resolutionM();
    const int wall = static_cast<int>(std::lround(4.0 / r));  // the endpoints lie on the cell edge at x = 4 m
    EXPECT_GT(std::fmax(grid.probability({wall - 1, 2}), grid.probability({wall, 2})), 0.6f);
    EXPECT_LT(grid.probability({static_cast<int>(std::floor(1.0 / r)), 2}), 0.5f);
    EXPECT_TRUE(std::isnan(grid.probability({static_cast<int>(std::floor(9.0 / r)), 2})));
    return 0;
  });
}

TEST_F(Slam2dLayerTest, AScanWithoutReturnsIsAckedWithoutAnEstimate) {
  send(roomScan(1, false));
  const std::vector<v1::ServerMessage> sent = connection_->waitFor(2);
  ASSERT_EQ(sent.size(), 2u);
  EXPECT_TRUE(sent[1].has_ack());
  EXPECT_EQ(service_->metrics().slam2d_scans_refused.load(), 1u);
  EXPECT_FALSE(service_->findMap("lab")->slam2d().hasLayer());
}

TEST_F(Slam2dLayerTest, ARestartReplaysTheSameGrid) {
  for (uint64_t seq = 1; seq <= 4; ++seq) send(roomScan(seq));
  ASSERT_EQ(connection_->waitFor(9).size(), 9u);
  const auto pgmOf = [](const MapWorker& map) {
    return map.slam2d().read([](const Grid2dSource& grid) {
      std::string cells;
      const Eigen::AlignedBox2i known = grid.knownCells();
      for (int y = known.min().y(); y <= known.max().y(); ++y) {
        for (int x = known.min().x(); x <= known.max().x(); ++x) cells += std::to_string(grid.probability({x, y}));
      }
      return cells;
    });
  };
  const std::string before = pgmOf(*service_->findMap("lab"));
  const uint64_t version = service_->findMap("lab")->slam2d().version();
  session_->onClose();
  service_.reset();
  service_ = std::make_unique<MappingService>(testing::configIn(dir_.path()));
  const std::shared_ptr<MapWorker> map = service_->findMap("lab");
  ASSERT_TRUE(map);
  EXPECT_EQ(map->slam2d().scans(), 4u);
  EXPECT_EQ(map->slam2d().version(), version);
  EXPECT_EQ(pgmOf(*map), before);
  connect();  // for TearDown
}

}  // namespace
}  // namespace rmap::app
