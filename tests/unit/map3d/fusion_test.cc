#include "map3d/fusion.h"

#include <gtest/gtest.h>

#include <random>

namespace rmap::map3d {
namespace {

/// Random block: clamped plateaus with noise, unknown holes, both states.
DenseCells randomBlock(uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> noise(-0.3f, 0.3f);
  DenseCells cells;
  for (int i = 0; i < kBlockCells; ++i) {
    const CellKey c = cellOf(BlockKey{}, i);
    if ((c.x * 7 + c.y * 3 + c.z + seed) % 11 == 0) continue;  // unknown
    float v = c.z < 5 ? -2.0f : (c.x == 9 ? 3.5f : -1.2f);
    if (rng() % 3 == 0) v += noise(rng);
    cells.log_odds[i] = v;
    cells.known.set(i);
  }
  return cells;
}

void expectValidDecomposition(const DenseCells& cells, const std::vector<PackedCuboid>& cuboids, float tolerance) {
  BlockBits covered;
  for (const PackedCuboid& c : cuboids) {
    for (int a = 0; a < 3; ++a) ASSERT_LE(c.lo(a), c.hi(a));
    for (int z = c.lo(2); z <= c.hi(2); ++z) {
      for (int y = c.lo(1); y <= c.hi(1); ++y) {
        for (int x = c.lo(0); x <= c.hi(0); ++x) {
          const int i = localIndex(x, y, z);
          ASSERT_FALSE(covered.test(i)) << "cuboids overlap at " << x << "," << y << "," << z;
          covered.set(i);
          ASSERT_TRUE(cells.known.test(i)) << "cuboid covers an unknown cell";
          EXPECT_LE(std::abs(cells.log_odds[i] - c.log_odds), tolerance / 2 + 1e-6f);
          EXPECT_EQ(cells.log_odds[i] >= 0.0f, c.log_odds >= 0.0f) << "a cuboid mixes states";
        }
      }
    }
  }
  EXPECT_EQ(covered.words, cells.known.words) << "cuboids must cover exactly the known cells";
}

TEST(Fusion, ZeroToleranceIsExactAndCoversKnownCells) {
  for (uint32_t seed = 0; seed < 20; ++seed) {
    const DenseCells cells = randomBlock(seed);
    const auto cuboids = fuseBlock(cells, 0.0f, 0.0f);
    expectValidDecomposition(cells, cuboids, 0.0f);
    DenseCells back;
    expandCuboids(cuboids, back);
    EXPECT_EQ(back.known.words, cells.known.words);
    cells.known.forEach([&](int i) { EXPECT_EQ(back.log_odds[i], cells.log_odds[i]); });
  }
}

TEST(Fusion, ToleranceBoundsEveryCellAndMergesMore) {
  for (uint32_t seed = 0; seed < 20; ++seed) {
    const DenseCells cells = randomBlock(seed);
    const auto exact = fuseBlock(cells, 0.0f, 0.0f);
    const auto loose = fuseBlock(cells, 0.7f, 0.0f);
    expectValidDecomposition(cells, loose, 0.7f);
    EXPECT_LT(loose.size(), exact.size());
  }
}

TEST(Fusion, SliceIndexFindsTheSameCuboidAsAScan) {
  for (uint32_t seed = 0; seed < 10; ++seed) {
    const DenseCells cells = randomBlock(seed);
    const auto cuboids = fuseBlock(cells, 0.0f, 0.0f);
    ASSERT_GE(cuboids.size(), SliceIndex::kMinCuboids);
    const SliceIndex index(cuboids);
    for (int i = 0; i < kBlockCells; ++i) {
      const CellKey c = cellOf(BlockKey{}, i);
      const int found = index.find(cuboids, c.x, c.y, c.z);
      ASSERT_EQ(found, findCuboid(cuboids, c.x, c.y, c.z));
      ASSERT_EQ(found >= 0, cells.known.test(i));
    }
  }
}

TEST(Fusion, UniformBlockIsOneCuboid) {
  DenseCells cells;
  cells.log_odds.fill(-2.0f);
  for (auto& w : cells.known.words) w = ~uint64_t{0};
  const auto cuboids = fuseBlock(cells, 0.0f, 0.0f);
  ASSERT_EQ(cuboids.size(), 1u);
  EXPECT_EQ(cuboids[0].cellCount(), kBlockCells);
  EXPECT_EQ(findCuboid(cuboids, 15, 15, 15), 0);
}

TEST(Fusion, StatesNeverMergeEvenWithinTolerance) {
  DenseCells cells;
  cells.log_odds[localIndex(0, 0, 0)] = -0.05f;
  cells.log_odds[localIndex(1, 0, 0)] = 0.05f;
  cells.known.set(localIndex(0, 0, 0));
  cells.known.set(localIndex(1, 0, 0));
  const auto cuboids = fuseBlock(cells, 1.0f, 0.0f);
  ASSERT_EQ(cuboids.size(), 2u);
  EXPECT_EQ(findCuboid(cuboids, 2, 0, 0), -1);
}

TEST(Fusion, WallSlabBecomesFewCuboids) {
  DenseCells cells;
  for (int z = 0; z < kBlockEdge; ++z) {
    for (int y = 0; y < kBlockEdge; ++y) {
      const int i = localIndex(7, y, z);
      cells.log_odds[i] = 3.5f;
      cells.known.set(i);
    }
  }
  EXPECT_EQ(fuseBlock(cells, 0.0f, 0.0f).size(), 1u);  // an octree needs 256 leaves for this slab
}

}  // namespace
}  // namespace rmap::map3d
