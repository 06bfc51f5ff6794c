#include "app/tiles.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>
#include <tuple>
#include <vector>

namespace rmap::app {
namespace {

using map3d::CellKey;

using TileTuple = std::tuple<int, int32_t, int32_t, int32_t>;

TileTuple tuple(const TileKey& k) { return {k.level, k.x, k.y, k.z}; }

/// A square wall of points at x = wall_x, seen from `origin`.
void insertWall(map3d::CuboidMap& map, const Eigen::Vector3f& origin, float wall_x) {
  std::vector<Eigen::Vector3f> points;
  for (int y = -5; y <= 5; ++y) {
    for (int z = -5; z <= 5; ++z) points.emplace_back(wall_x, origin.y() + 0.1f * y, origin.z() + 0.1f * z);
  }
  map.insertScan(origin, points);
}

/// Expected tiles (all levels) of the blocks whose version is above `since`, with the highest block version.
std::map<TileTuple, uint64_t> expectedTiles(const map3d::CuboidMap& map, uint64_t since) {
  std::map<TileTuple, uint64_t> out;
  map.forEachBlockVersion([&](const map3d::BlockKey& b, uint64_t version) {
    if (version <= since) return;
    for (int level = 0; level < kTileLevels; ++level) {
      const double edge = static_cast<double>(tileEdgeBaseCells(level));
      const auto tile = [&](int32_t block) {
        return static_cast<int32_t>(std::floor(block * map3d::kBlockEdge / edge));
      };
      uint64_t& v = out[{level, tile(b.x), tile(b.y), tile(b.z)}];
      v = std::max(v, version);
    }
  });
  return out;
}

std::map<TileTuple, uint64_t> asMap(const std::vector<TileVersion>& tiles) {
  std::map<TileTuple, uint64_t> out;
  for (const TileVersion& t : tiles) EXPECT_TRUE(out.emplace(tuple(t.key), t.version).second) << "duplicate tile";
  return out;
}

TEST(TileCellRange, Level0Tiles) {
  CellKey min, max;
  tileCellRange({0, 0, 0, 0}, min, max);
  EXPECT_EQ(min, (CellKey{0, 0, 0}));
  EXPECT_EQ(max, (CellKey{63, 63, 63}));
  tileCellRange({0, -1, -2, 3}, min, max);
  EXPECT_EQ(min, (CellKey{-64, -128, 192}));
  EXPECT_EQ(max, (CellKey{-1, -65, 255}));
}

TEST(TileCellRange, Level2Tiles) {
  EXPECT_EQ(tileEdgeBaseCells(2), 256);
  CellKey min, max;
  tileCellRange({2, 1, -1, 0}, min, max);
  EXPECT_EQ(min, (CellKey{256, -256, 0}));
  EXPECT_EQ(max, (CellKey{511, -1, 255}));
}

TEST(TileCellRange, EdgeTilesAreClampedToTheAddressableRange) {
  CellKey min, max;
  EXPECT_TRUE(tileCellRange({6, -8, 7, 0}, min, max));
  EXPECT_EQ(min, (CellKey{-map3d::kCellLimit, 7 * 4096, 0}));
  EXPECT_EQ(max, (CellKey{-7 * 4096 - 1, map3d::kCellLimit - 1, 4095}));
}

TEST(TileIndex, UpdateReportsTheTilesOfChangedBlocksAtEveryLevel) {
  map3d::CuboidMap map(0.1);
  TileIndex index;
  insertWall(map, {0.05f, 0.05f, 0.05f}, 2.0f);

  const std::map<TileTuple, uint64_t> expected = expectedTiles(map, 0);
  const std::map<TileTuple, uint64_t> reported = asMap(index.update(map));
  EXPECT_EQ(reported, expected);
  // The wall spans negative and positive y and z: level 0 sees four tiles, level 1+ as many.
  EXPECT_EQ(index.tiles(0).size(), 4u);
  EXPECT_TRUE(reported.count({0, 0, -1, -1}));
  EXPECT_TRUE(reported.count({6, 0, -1, -1}));
  for (const auto& [tile, version] : reported) EXPECT_EQ(version, map.version());
  EXPECT_EQ(index.mapVersion(), map.version());
}

TEST(TileIndex, SecondUpdateWithoutChangeReportsNothing) {
  map3d::CuboidMap map(0.1);
  TileIndex index;
  insertWall(map, {0.05f, 0.05f, 0.05f}, 2.0f);
  ASSERT_FALSE(index.update(map).empty());
  EXPECT_TRUE(index.update(map).empty());
}

TEST(TileIndex, LaterScanElsewhereReportsOnlyItsTiles) {
  map3d::CuboidMap map(0.1);
  TileIndex index;
  insertWall(map, {0.05f, 0.05f, 0.05f}, 2.0f);
  const std::map<TileTuple, uint64_t> first = asMap(index.update(map));
  const uint64_t first_version = map.version();

  insertWall(map, {30.05f, 30.05f, 0.05f}, 32.0f);
  const std::map<TileTuple, uint64_t> second = asMap(index.update(map));
  EXPECT_EQ(second, expectedTiles(map, first_version));
  size_t new_level0 = 0;
  for (const auto& [tile, version] : second) {
    EXPECT_EQ(version, map.version());
    if (std::get<0>(tile) != 0) continue;
    ++new_level0;
    EXPECT_FALSE(first.count(tile)) << "level-0 tile of the first scan reported again";
  }
  EXPECT_GT(new_level0, 0u);
  // Old tiles keep their version; the index knows the tiles of both scans.
  EXPECT_EQ(index.version({0, 0, -1, -1}), first_version);
  EXPECT_EQ(index.tiles(0).size(), 4u + new_level0);
}

TEST(TileIndex, UnknownTileHasNoVersion) {
  TileIndex index;
  EXPECT_FALSE(index.version({0, 1, 2, 3}));
  EXPECT_TRUE(index.tiles(0).empty());
}

TEST(TileCuboids, Level0CuboidsLieInTheTileAndCoverItsKnownCells) {
  map3d::CuboidMap map(0.1);
  insertWall(map, {0.05f, 0.05f, 0.05f}, 2.0f);
  TileIndex index;
  index.update(map);
  const float tolerance = map.fusionParams().tolerance_log_odds;
  ASSERT_FALSE(index.tiles(0).empty());
  for (const TileVersion& tile : index.tiles(0)) {
    CellKey min, max;
    tileCellRange(tile.key, min, max);
    const auto inside = [&](const CellKey& c) {
      return c.x >= min.x && c.x <= max.x && c.y >= min.y && c.y <= max.y && c.z >= min.z && c.z <= max.z;
    };
    std::map<std::tuple<int, int, int>, float> known;
    map.forEachKnownCell([&](const CellKey& c, float v) {
      if (inside(c)) known[{c.x, c.y, c.z}] = v;
    });
    std::set<std::tuple<int, int, int>> covered;
    for (const map3d::CuboidBox& box : tileCuboids(map, tile.key)) {
      ASSERT_TRUE(inside(box.min) && inside(box.max));
      for (int z = box.min.z; z <= box.max.z; ++z) {
        for (int y = box.min.y; y <= box.max.y; ++y) {
          for (int x = box.min.x; x <= box.max.x; ++x) {
            const auto cell = known.find({x, y, z});
            ASSERT_NE(cell, known.end()) << "cuboid covers an unknown cell";
            EXPECT_NEAR(box.log_odds, cell->second, tolerance / 2 + 1e-6f);
            EXPECT_TRUE(covered.insert({x, y, z}).second) << "cuboids overlap";
          }
        }
      }
    }
    EXPECT_EQ(covered.size(), known.size());
    EXPECT_FALSE(known.empty());
  }
}

TEST(TileCellRange, TilesWhollyOutsideTheAddressableRangeHaveNoCells) {
  CellKey min, max;
  EXPECT_TRUE(tileCellRange({0, 511, 0, 0}, min, max));
  EXPECT_EQ(max.x, map3d::kCellLimit - 1);
  EXPECT_FALSE(tileCellRange({0, 512, 0, 0}, min, max));
  EXPECT_TRUE(tileCellRange({0, -512, 0, 0}, min, max));
  EXPECT_EQ(min.x, -map3d::kCellLimit);
  EXPECT_FALSE(tileCellRange({0, 0, -513, 0}, min, max));
  EXPECT_FALSE(tileCellRange({6, 0, 0, 8}, min, max));
  EXPECT_FALSE(tileCellRange({6, 0, 0, -9}, min, max));
}

TEST(TileCuboids, TileBeyondTheAddressableRangeIsEmpty) {
  map3d::CuboidMap map(0.1);
  map.insertScan({3276.0f, 0.05f, 0.05f}, std::vector<Eigen::Vector3f>{{3276.75f, 0.05f, 0.05f}});
  ASSERT_FALSE(tileCuboids(map, {0, 511, 0, 0}).empty());
  EXPECT_TRUE(tileCuboids(map, {0, 512, 0, 0}).empty());
}

}  // namespace
}  // namespace rmap::app
