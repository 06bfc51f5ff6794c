#include "map3d/ray_traversal.h"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <random>
#include <vector>

namespace rmap::map3d {
namespace {

std::vector<CellKey> freeCells(const Grid& grid, Eigen::Vector3f a, Eigen::Vector3f b) {
  std::vector<CellKey> cells;
  EXPECT_TRUE(traverseFreeCells(grid, a, b, [&](const CellKey& c) { cells.push_back(c); }));
  return cells;
}

TEST(RayTraversal, AxisAlignedRayListsEveryCellBeforeTheEnd) {
  const Grid grid(1.0);
  const auto cells = freeCells(grid, {0.5f, 0.5f, 0.5f}, {4.5f, 0.5f, 0.5f});
  const std::vector<CellKey> expected = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  EXPECT_EQ(cells, expected);
}

TEST(RayTraversal, NegativeDirectionAndNegativeCells) {
  const Grid grid(0.5);
  const auto cells = freeCells(grid, {0.1f, 0.1f, -0.1f}, {-1.1f, 0.1f, -0.1f});
  const std::vector<CellKey> expected = {{0, 0, -1}, {-1, 0, -1}, {-2, 0, -1}};
  EXPECT_EQ(cells, expected);
}

TEST(RayTraversal, DiagonalStepsOneAxisAtATime) {
  const Grid grid(1.0);
  // slope 0.5 in y: crosses x borders at 1, 2, 3 and the y border at x = 1.8
  const auto cells = freeCells(grid, {0.2f, 0.2f, 0.5f}, {3.4f, 1.8f, 0.5f});
  const std::vector<CellKey> expected = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {2, 1, 0}};
  EXPECT_EQ(cells, expected);
}

TEST(RayTraversal, SameCellVisitsNothing) {
  const Grid grid(1.0);
  EXPECT_TRUE(freeCells(grid, {0.2f, 0.2f, 0.2f}, {0.8f, 0.9f, 0.1f}).empty());
}

TEST(RayTraversal, RejectsNonFiniteAndOutOfRangePoints) {
  const Grid grid(0.1);
  int visited = 0;
  auto count = [&](const CellKey&) { ++visited; };
  EXPECT_FALSE(traverseFreeCells(grid, {0, 0, 0}, {NAN, 0, 0}, count));
  EXPECT_FALSE(traverseFreeCells(grid, {0, 0, 0}, {INFINITY, 0, 0}, count));
  EXPECT_FALSE(traverseFreeCells(grid, {0, 0, 0}, {4000.0f, 0, 0}, count));  // beyond ±3276.8 m at 0.1 m
  EXPECT_EQ(visited, 0);
}

// The cells must be exactly OctoMap's, including its early stop on rounding.
TEST(RayTraversal, MatchesOctomapComputeRayKeysOnRandomRays) {
  for (double res : {0.05, 0.1, 0.37}) {
    octomap::OcTree tree(res);
    const Grid grid(res);
    std::mt19937 rng(42);
    std::uniform_real_distribution<float> coord(-12.0f, 12.0f);
    octomap::KeyRay ray;
    for (int i = 0; i < 20000; ++i) {
      const Eigen::Vector3f a(coord(rng), coord(rng), coord(rng) * 0.2f);
      Eigen::Vector3f b(coord(rng), coord(rng), coord(rng));
      if (i % 7 == 0) b.z() = a.z();  // axis-parallel components
      ASSERT_TRUE(tree.computeRayKeys({a.x(), a.y(), a.z()}, {b.x(), b.y(), b.z()}, ray));
      std::vector<CellKey> expected;
      for (const octomap::OcTreeKey& k : ray) expected.push_back({k[0] - 32768, k[1] - 32768, k[2] - 32768});
      ASSERT_EQ(freeCells(grid, a, b), expected) << "ray " << i << " at resolution " << res;
    }
  }
}

}  // namespace
}  // namespace rmap::map3d
