#include "app/map_worker.h"

#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <thread>

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

}  // namespace
}  // namespace rmap::app
