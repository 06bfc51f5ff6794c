#include "sim/truth.h"

#include <gtest/gtest.h>

#include <random>

#include "map3d/cell_key.h"

namespace rmap::sim {
namespace {

// With voxel_m equal to the map resolution, world voxels and map base cells
// are the same cubes, so truth is exact cell for cell.
TEST(Truth, WorldVoxelsAreMapCells) {
  const double res = 0.05;  // not exactly representable: exercises the shared arithmetic
  VoxelWorld world(res, Eigen::Vector3i::Constant(-40), Eigen::Vector3i::Constant(80));
  const map3d::Grid grid(res);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    world.fillBox(Eigen::AlignedBox3d(p, p + Eigen::Vector3d::Constant(0.17)), 0.5f);
  }
  int occupied = 0;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    Eigen::Vector3i voxel;
    ASSERT_TRUE(world.voxelOf(p, voxel));
    const map3d::CellKey cell{grid.index(p.x()), grid.index(p.y()), grid.index(p.z())};
    EXPECT_EQ(voxel, Eigen::Vector3i(cell.x, cell.y, cell.z));
    const bool truth = trueOccupied(world, grid.center(cell));
    EXPECT_EQ(truth, world.occupiedVoxel(voxel));
    EXPECT_EQ(truth, world.occupied(p));
    occupied += truth;
  }
  EXPECT_GT(occupied, 100);
  EXPECT_FALSE(trueOccupied(world, Eigen::Vector3d(10, 0, 0)));  // outside the world: free
}

}  // namespace
}  // namespace rmap::sim
