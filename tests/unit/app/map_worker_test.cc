#include "app/map_worker.h"

#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <thread>

#include "app/slam2d_layer.h"
#include "client/laser2d_robot.h"
#include "service_test_support.h"
#include "sim/building.h"
#include "sim/trajectory.h"

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

/// A 2D-laser robot (laser at the base, no Hello describing it) that drives out along a tour
/// of a simulated building and 80 steps back over it, then stops: closures on the way back,
/// the last ones within LoopClosureOptions::confirm_after_s when it stops.
std::vector<v1::RobotMessage> scansOutAndBackThenStop() {
  const sim::VoxelWorld world = sim::makeBuilding(sim::BuildingOptions{}, 7);
  sim::TrajectoryOptions tour;
  tour.num_poses = 120;
  tour.step_m = 0.26;
  client::Laser2dRobotOptions laser;
  laser.laser = sim::Laser2dModel::sickLike();
  laser.mount_forward_m = 0.0;
  client::Laser2dRobot robot(world, sim::planTrajectory(world, tour, 3), laser, 41);
  std::vector<v1::RobotMessage> messages;
  constexpr uint64_t kStops = 200;  // steps before the robot stops
  for (uint64_t seq = 1; seq <= kStops; ++seq) {
    v1::RobotMessage m;
    m.set_seq(seq);
    *m.mutable_scan() = robot.next().scan;
    m.mutable_scan()->set_stamp_ns(static_cast<int64_t>(seq) * 100'000'000);
    messages.push_back(std::move(m));
  }
  return messages;
}

/// Applies `messages` to map "lab" of `service` and waits until the last one is applied.
void applyAll(MappingService& service, MapWorker& map, const std::vector<v1::RobotMessage>& messages) {
  std::promise<void> applied;
  for (size_t k = 0; k < messages.size(); ++k)
    service.apply(map, static_cast<int64_t>(k + 1), std::make_shared<v1::RobotMessage>(messages[k]), "bot",
                  k + 1 == messages.size() ? std::function<void()>([&] { applied.set_value(); }) : nullptr);
  applied.get_future().wait();
}

size_t storedGeometryClosures(MappingService& service) {
  return service.store().loopClosures({"lab", "", "geometry", 0, 100000}).size();
}

// A robot that stops right after closing a loop: the closures still waiting for a
// later optimisation are stored once the map's ingest paused, as the end of a log gives them.
TEST(MapWorker, ClosuresWaitingWhenARobotStopsAreStoredOnceTheMapIsIdle) {
  const std::vector<v1::RobotMessage> messages = scansOutAndBackThenStop();

  // The same scans through a 2D SLAM layer of its own: what the map must store.
  Metrics metrics;
  Slam2dLayer reference(slam2d::Slam2dOptions{}, {}, metrics);
  size_t at_scans = 0;
  for (const v1::RobotMessage& m : messages)
    if (const std::optional<Slam2dResult> r = reference.addScan("bot", m.scan(), std::nullopt))
      at_scans += r->closures.size();
  const size_t at_pause = reference.confirmLoopClosures().size();
  ASSERT_GT(at_pause, 0u) << "no closure waited at the end (" << at_scans
                          << " came with the scans): this would not test the pause";

  store::TempDir dir;
  MappingService service(testing::configIn(dir.path()));
  const std::shared_ptr<MapWorker> map = service.openMap("lab", 0.1);
  applyAll(service, *map, messages);
  size_t stored = 0;
  for (int i = 0; i < 100 && stored < at_scans + at_pause; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    stored = storedGeometryClosures(service);
  }
  EXPECT_EQ(stored, at_scans + at_pause) << at_scans << " closures came with the scans, " << at_pause
                                         << " should have come once the map was idle";
}

// rmapd's config sets the 2D SLAM of every map (Slam2dConfig::options): here a coarser
// grid and no geometric loop closure, on the drive that closes loops by default (above).
TEST(MapWorker, TheSlamOfAMapTakesTheConfiguredOptions) {
  store::TempDir dir;
  Config config = testing::configIn(dir.path());
  config.slam2d.options.resolution_m = 0.1;
  config.slam2d.options.loop_closure.enabled = false;
  MappingService service(config);
  const std::shared_ptr<MapWorker> map = service.openMap("lab", 0.1);
  applyAll(service, *map, scansOutAndBackThenStop());
  // Past the idle delay after which waiting closures would be stored.
  std::this_thread::sleep_for(std::chrono::milliseconds(2500));

  EXPECT_EQ(map->slam2d().scans(), 200u);
  EXPECT_EQ(storedGeometryClosures(service), 0u);
  map->slam2d().read([](const Grid2dSource& grid) { EXPECT_DOUBLE_EQ(grid.resolutionM(), 0.1); });
}

}  // namespace
}  // namespace rmap::app
