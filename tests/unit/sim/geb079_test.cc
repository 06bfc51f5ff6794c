// The simulator on real building geometry: OctoMap's geb079.bt (Freiburg
// building 079, 0.08 m) as world, a tour through its observed free space,
// and a 64 × 1024 lidar scan from the tour. Skipped when the file is absent.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "map3d/octomap_bt.h"
#include "sim/bt_world.h"
#include "sim/lidar.h"
#include "sim/navigable.h"
#include "sim/trajectory.h"

namespace rmap::sim {
namespace {

const std::filesystem::path kGeb079 = std::filesystem::path(RMAP_SHARED_DATA_DIR) / "octomap" / "geb079.bt";

TEST(Geb079, WorldTourAndScan) {
  if (!std::filesystem::exists(kGeb079)) GTEST_SKIP() << kGeb079 << " not found";
  std::ifstream in(kGeb079, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  const VoxelWorld world = worldFromBt(map3d::parseBt(bytes.str()), 0.5f, 79);
  const Eigen::AlignedBox3d b = world.bounds();
  std::printf("[ geb079 ] %d x %d x %d voxels of %.2f m, x %.2f..%.2f, y %.2f..%.2f, z %.2f..%.2f m\n",
              world.dims().x(), world.dims().y(), world.dims().z(), world.voxelSize(), b.min().x(), b.max().x(),
              b.min().y(), b.max().y(), b.min().z(), b.max().z());
  std::printf("[ geb079 ] %zu occupied voxels, %zu known free, %.1f MiB\n", world.occupiedCount(),
              world.knownFreeCount(), world.memoryBytes() / 1048576.0);
  EXPECT_NEAR(world.voxelSize(), 0.08, 1e-12);
  EXPECT_GT(world.occupiedCount(), 100000u);
  EXPECT_TRUE(world.hasKnownFree());

  // At 1.0 m the map's unobserved pockets (thin shadows of sparse rays) cut
  // the corridor at sensor height; at 1.3 m its observed free space is
  // continuous over the whole corridor.
  TrajectoryOptions options;
  options.sensor_height_m = 1.3;
  options.num_poses = 120;
  const NavigableSpace space(world, options);
  ASSERT_GT(space.size(), 0u);
  std::printf("[ geb079 ] floor at z = %.2f m; %zu standing cells of %.2f m, largest connected part %zu (%.0f m^2)\n",
              space.dominantFloorZ(), space.size(), space.cellSize(), space.componentSize(0),
              space.componentSize(0) * space.cellSize() * space.cellSize());
  EXPECT_NEAR(space.dominantFloorZ(), 0.0, 0.2);

  const auto poses = planTrajectory(world, options, 79);
  ASSERT_EQ(poses.size(), 120u);
  Eigen::AlignedBox3d spread;
  for (const auto& pose : poses) {
    ASSERT_TRUE(world.knownFree(pose.translation()));
    ASSERT_FALSE(world.occupied(pose.translation()));
    spread.extend(pose.translation());
  }
  std::printf("[ geb079 ] tour of %zu poses spans %.1f x %.1f m\n", poses.size(), spread.sizes().x(),
              spread.sizes().y());
  EXPECT_GT(spread.sizes().x(), 15.0);  // the corridor is ~31 m long, the tour covers 36 m of path

  const LidarModel lidar;
  std::mt19937_64 rng(79);
  for (size_t i : {size_t{0}, poses.size() / 2, poses.size() - 1}) {
    const LidarScan scan = simulateLidar(world, poses[i], lidar, rng);
    const double returned = static_cast<double>(scan.points_m.size()) / (lidar.rings * lidar.columns);
    std::printf("[ geb079 ] scan at pose %zu (%.2f, %.2f, %.2f): %zu of %d beams return (%.1f %%)\n", i,
                poses[i].translation().x(), poses[i].translation().y(), poses[i].translation().z(),
                scan.points_m.size(), lidar.rings * lidar.columns, 100 * returned);
    EXPECT_GT(returned, 0.8);
  }
}

}  // namespace
}  // namespace rmap::sim
