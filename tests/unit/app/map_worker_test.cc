#include "app/map_worker.h"

#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <random>
#include <thread>

#include "../slam2d/sim_scans.h"
#include "app/slam2d_layer.h"
#include "service_test_support.h"

namespace rmap::app {
namespace {

/// A flat wall 2 m ahead of the origin, 1.6 m × 1.6 m, a point every 2 cm.
std::vector<Eigen::Vector3f> wallPoints() {
  std::vector<Eigen::Vector3f> points;
  for (float y = -0.8f; y <= 0.8f; y += 0.02f) {
    for (float z = 0.2f; z <= 1.8f; z += 0.02f) points.emplace_back(2.0f, y, z);
  }
  return points;
}

TEST(MapWorker, AnIdleMapFusesItsHotBlocksWithoutChangingACell) {
  store::TempDir dir;
  MappingService service(testing::configIn(dir.path()));
  const std::shared_ptr<MapWorker> map = service.openMap("lab", 0.1);
  std::promise<void> applied;
  service.apply(*map, 1, std::make_shared<v1::RobotMessage>(testing::cloudMessage(1, {0.0, 0.0, 1.0}, wallPoints())),
                "bot", [&] { applied.set_value(); });
  applied.get_future().wait();
  const map3d::MapStats hot = map->map().stats();
  ASSERT_GT(hot.hot_blocks, 0u);
  const map3d::CellQuery wall_before = map->map().query({2.0, 0.0, 1.0});
  const map3d::CellQuery ray_before = map->map().query({1.0, 0.0, 1.0});

  map3d::MapStats idle = hot;
  for (int i = 0; i < 50 && idle.hot_blocks > 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    idle = map->map().stats();
  }
  EXPECT_EQ(idle.hot_blocks, 0u) << "still hot 5 s after the last message";
  EXPECT_LT(idle.cuboids, hot.cuboids);
  EXPECT_EQ(idle.known_cells, hot.known_cells);
  EXPECT_EQ(idle.occupied_cells, hot.occupied_cells);
  EXPECT_EQ(map->map().query({2.0, 0.0, 1.0}).state, wall_before.state);
  EXPECT_EQ(map->map().query({1.0, 0.0, 1.0}).state, ray_before.state);
  EXPECT_EQ(wall_before.state, map3d::CellState::kOccupied);
  EXPECT_EQ(ray_before.state, map3d::CellState::kFree);
}

/// A simulated scan with its odometry (the true pose) as a robot sends it.
v1::RobotMessage scanMessage(uint64_t seq, const sim::Laser2dScan& s, const slam2d::Pose2& odometry) {
  v1::RobotMessage m;
  m.set_seq(seq);
  v1::LaserScan2D& scan = *m.mutable_scan();
  scan.set_stamp_ns(static_cast<int64_t>(seq) * 100'000'000);
  scan.set_angle_min_rad(s.angle_min_rad);
  scan.set_angle_increment_rad(s.angle_increment_rad);
  scan.set_range_min_m(s.range_min_m);
  scan.set_range_max_m(s.range_max_m);
  for (float r : s.ranges_m) scan.add_ranges_m(r);
  for (float i : s.intensities) scan.add_intensities(i);
  scan.mutable_odometry()->set_x_m(odometry.x_m);
  scan.mutable_odometry()->set_y_m(odometry.y_m);
  scan.mutable_odometry()->set_theta_rad(odometry.theta_rad);
  return m;
}

// A robot that stops right after closing a loop: the closures still waiting for a
// later optimisation (LoopClosureOptions::confirm_after_s) are stored once the map's
// ingest paused, as the end of a log gives them.
TEST(MapWorker, ClosuresWaitingWhenARobotStopsAreStoredOnceTheMapIsIdle) {
  const sim::VoxelWorld world = slam2d::testing::simBuilding();
  const std::vector<slam2d::Pose2> tour = slam2d::testing::simTour(world, 240, 0.25);
  // Out along the tour, then its first stretch again: 3 s of scans, less than the hold.
  std::vector<slam2d::Pose2> path = slam2d::testing::smoothTurns({tour.begin(), tour.begin() + 120}, 0.1);
  const std::vector<slam2d::Pose2> again = slam2d::testing::smoothTurns({tour.begin(), tour.begin() + 30}, 0.1);
  path.insert(path.end(), again.begin(), again.end());
  const sim::Laser2dModel model = sim::Laser2dModel::sickLike();
  std::mt19937_64 rng(41);
  std::vector<v1::RobotMessage> messages;
  for (size_t k = 0; k < path.size(); ++k)
    messages.push_back(scanMessage(k + 1, sim::simulateLaser2d(world, slam2d::testing::sensorAt(path[k]), model, rng),
                                   path[k]));

  // The same scans through a 2D SLAM layer of its own: what the map must store.
  Metrics metrics;
  Slam2dLayer reference({}, metrics);
  size_t at_scans = 0;
  for (const v1::RobotMessage& m : messages)
    if (const std::optional<Slam2dResult> r = reference.addScan("bot", m.scan(), std::nullopt))
      at_scans += r->closures.size();
  const size_t at_pause = reference.confirmLoopClosures().size();
  ASSERT_GT(at_pause, 0u) << "no closure waited at the end: this would not test the pause";

  store::TempDir dir;
  MappingService service(testing::configIn(dir.path()));
  const std::shared_ptr<MapWorker> map = service.openMap("lab", 0.1);
  std::promise<void> applied;
  for (size_t k = 0; k < messages.size(); ++k)
    service.apply(*map, static_cast<int64_t>(k + 1), std::make_shared<v1::RobotMessage>(messages[k]), "bot",
                  k + 1 == messages.size() ? std::function<void()>([&] { applied.set_value(); }) : nullptr);
  applied.get_future().wait();
  size_t stored = 0;
  for (int i = 0; i < 100 && stored < at_scans + at_pause; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    stored = service.store().loopClosures({"lab", "", "geometry", 0, 100000}).size();
  }
  EXPECT_EQ(stored, at_scans + at_pause) << at_scans << " closures came with the scans, " << at_pause
                                         << " should have come once the map was idle";
}

}  // namespace
}  // namespace rmap::app
