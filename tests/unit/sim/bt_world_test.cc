#include "sim/bt_world.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "map3d/cell_key.h"

namespace rmap::sim {
namespace {

using Eigen::Vector3i;

map3d::BtTree smallTree() {
  map3d::BtTree tree;
  tree.resolution_m = 0.1;
  tree.leaves.push_back({{0, 0, 0}, 2, true});     // 8 occupied cells
  tree.leaves.push_back({{-3, 1, 2}, 1, true});    // 1 occupied cell
  tree.leaves.push_back({{4, 0, 0}, 4, false});    // 64 free cells
  tree.leaves.push_back({{2, 0, 0}, 1, false});
  return tree;
}

TEST(BtWorld, VoxelsAreTheTreeCells) {
  const VoxelWorld w = worldFromBt(smallTree(), 0.5f, 1);
  EXPECT_DOUBLE_EQ(w.voxelSize(), 0.1);
  EXPECT_EQ(w.minVoxel(), Vector3i(-3, 0, 0));
  EXPECT_EQ(w.dims(), Vector3i(11, 4, 4));  // x −3..7, y 0..3, z 0..3
  EXPECT_EQ(w.occupiedCount(), 9u);
  EXPECT_EQ(w.knownFreeCount(), 65u);
  const map3d::Grid grid(0.1);
  for (int z = 0; z < 2; ++z) {
    for (int y = 0; y < 2; ++y) {
      for (int x = 0; x < 2; ++x) EXPECT_TRUE(w.occupied(grid.center(map3d::CellKey{x, y, z})));
    }
  }
  EXPECT_TRUE(w.occupied(grid.center(map3d::CellKey{-3, 1, 2})));
  EXPECT_FALSE(w.occupied(grid.center(map3d::CellKey{2, 0, 0})));
  EXPECT_TRUE(w.knownFree(grid.center(map3d::CellKey{2, 0, 0})));
  EXPECT_TRUE(w.knownFree(grid.center(map3d::CellKey{7, 3, 3})));
  EXPECT_FALSE(w.knownFree(grid.center(map3d::CellKey{3, 0, 0})));  // unknown: neither
  EXPECT_FALSE(w.occupied(grid.center(map3d::CellKey{3, 0, 0})));
  // A ray along +x at cell row (y 0, z 0) enters cell 0 through its x = 0 face.
  const auto hit = w.castRay(Eigen::Vector3d(-1.0, 0.05, 0.05), Eigen::Vector3d::UnitX(), 5.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->range_m, 1.0, 1e-12);
}

TEST(BtWorld, ReflectivityIsASmoothSeededField) {
  // A 12.8 m × 12.8 m floor slab of 16-cell leaves.
  map3d::BtTree tree;
  tree.resolution_m = 0.05;
  for (int y = 0; y < 256; y += 16) {
    for (int x = 0; x < 256; x += 16) tree.leaves.push_back({{x, y, 0}, 16, true});
  }
  const VoxelWorld a = worldFromBt(tree, 0.4f, 7);
  const VoxelWorld b = worldFromBt(tree, 0.4f, 7);
  const VoxelWorld c = worldFromBt(tree, 0.4f, 8);
  double sum = 0, sum2 = 0, lo = 1, hi = 0, neighbour_gap = 0;
  int n = 0, differing = 0;
  for (int y = 0; y < 256; y += 3) {
    for (int x = 0; x < 256; x += 3) {
      const Vector3i v(x, y, 15);
      const float r = a.reflectivityVoxel(v);
      ASSERT_EQ(r, b.reflectivityVoxel(v));
      differing += r != c.reflectivityVoxel(v);
      ASSERT_GE(r, 0.02f - 1e-3f);
      ASSERT_LE(r, 1.0f);
      lo = std::min<double>(lo, r);
      hi = std::max<double>(hi, r);
      sum += r;
      sum2 += r * r;
      neighbour_gap += std::abs(r - a.reflectivityVoxel(v + Vector3i(1, 0, 0)));
      ++n;
    }
  }
  const double mean = sum / n, sigma = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 0.4, 0.1);
  EXPECT_GT(sigma, 0.03);    // varied ...
  EXPECT_GT(hi - lo, 0.15);
  EXPECT_LT(neighbour_gap / n, 0.02);  // ... but smooth from voxel to voxel
  EXPECT_GT(differing, n / 2);         // and another seed gives another field
}

TEST(BtWorld, RejectsBadInput) {
  map3d::BtTree tree = smallTree();
  EXPECT_THROW(worldFromBt(tree, 0.0f, 1), std::invalid_argument);
  EXPECT_THROW(worldFromBt(tree, 1.5f, 1), std::invalid_argument);
  tree.resolution_m = 0.0;
  EXPECT_THROW(worldFromBt(tree, 0.5f, 1), std::invalid_argument);
  map3d::BtTree free_only;
  free_only.resolution_m = 0.1;
  free_only.leaves.push_back({{0, 0, 0}, 4, false});
  EXPECT_THROW(worldFromBt(free_only, 0.5f, 1), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::sim
