#include "map3d/octomap_interop.h"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

namespace rmap::map3d {
namespace {

const std::string kGeb079 = std::string(RMAP_SHARED_DATA_DIR) + "/octomap/geb079.bt";

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

/// Every base cell known to OctoMap has the same state in the map and back.
void expectSameCells(const CuboidMap& map, const octomap::OcTree& tree) {
  uint64_t octo_cells = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    const int size = 1 << (16 - it.getDepth());
    const octomap::OcTreeKey k = it.getKey();
    const CellKey min{(k[0] & ~(size - 1)) - 32768, (k[1] & ~(size - 1)) - 32768, (k[2] & ~(size - 1)) - 32768};
    const CellState expected = tree.isNodeOccupied(*it) ? CellState::kOccupied : CellState::kFree;
    octo_cells += uint64_t(size) * size * size;
    // corners and centre of each leaf cube
    for (const CellKey& c : {min, CellKey{min.x + size - 1, min.y + size - 1, min.z + size - 1},
                             CellKey{min.x + size / 2, min.y, min.z + size - 1}}) {
      ASSERT_EQ(map.queryCell(c).state, expected);
    }
  }
  EXPECT_EQ(map.stats().known_cells, octo_cells);
}

TEST(OctomapInterop, ImportsGeb079AsOctomapReadsIt) {
  if (!std::filesystem::exists(kGeb079)) GTEST_SKIP() << kGeb079 << " not found (shared data absent)";
  const auto map = mapFromBt(parseBt(readAll(kGeb079)));
  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(kGeb079));
  EXPECT_DOUBLE_EQ(map->resolution(), tree.getResolution());
  expectSameCells(*map, tree);
  // cuboids compress the octree's leaves
  EXPECT_LT(map->stats().cuboids, tree.getNumLeafNodes());
}

/// Scans of random points in a flat box of half-width `half_m` (z a tenth of it), sensors along x.
void insertRandomScans(CuboidMap& map, uint32_t seed, int scans, float half_m) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-half_m, half_m);
  for (int s = 0; s < scans; ++s) {
    std::vector<Eigen::Vector3f> points;
    for (int i = 0; i < 1000 * scans; ++i) points.push_back({u(rng), u(rng), u(rng) * 0.1f * half_m});
    map.insertScan({0.2f * s, 0.0f, 0.1f}, points);
  }
}

TEST(OctomapInterop, ExportIsReadBackByOctomapWithTheSameCells) {
  CuboidMap map(0.05);
  insertRandomScans(map, 5, 3, 3.0f);
  std::istringstream in(mapToBt(map));
  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(in));
  EXPECT_DOUBLE_EQ(tree.getResolution(), 0.05);
  uint64_t cells = 0;
  map.forEachKnownCell([&](const CellKey& c, float v) {
    ++cells;
    const octomap::OcTreeNode* n = tree.search(octomap::OcTreeKey(c.x + 32768, c.y + 32768, c.z + 32768));
    ASSERT_NE(n, nullptr);
    ASSERT_EQ(tree.isNodeOccupied(n), v >= 0.0f);
  });
  uint64_t octo_cells = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    const uint64_t size = uint64_t{1} << (16 - it.getDepth());
    octo_cells += size * size * size;
  }
  EXPECT_EQ(cells, octo_cells);
  // and our own import of the export has the same states
  const auto back = mapFromBt(parseBt(mapToBt(map)));
  map.forEachKnownCell([&](const CellKey& c, float v) {
    ASSERT_EQ(back->queryCell(c).state, v >= 0.0f ? CellState::kOccupied : CellState::kFree);
  });
}

TEST(OctomapInterop, ExportFromCuboidsEqualsTheCellByCellTree) {
  CuboidMap map(0.1);
  insertRandomScans(map, 11, 4, 4.0f);
  std::vector<BtCell> cells;
  map.forEachKnownCell([&](const CellKey& c, float v) { cells.push_back({c, v >= 0.0f}); });
  // The same pruned tree, byte for byte, whether written from cells or from the cuboids' octants.
  EXPECT_EQ(mapToBt(map), writeBt(map.resolution(), cells));
  EXPECT_EQ(mapToBt(CuboidMap(0.1)), writeBt(0.1, {}));
}

/// The map built from blocksFromLeaves, as an import builds it.
std::unique_ptr<CuboidMap> mapFromBlocks(double resolution_m, MapBlocks blocks) {
  auto map = std::make_unique<CuboidMap>(resolution_m);
  map->replaceBlocks(std::move(blocks));
  return map;
}

TEST(OctomapInterop, BlocksFromBtLeavesHoldOctomapsCells) {
  octomap::OcTree tree(0.1);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-4.0f, 4.0f);
  for (int s = 0; s < 3; ++s) {
    octomap::Pointcloud cloud;
    for (int i = 0; i < 2000; ++i) cloud.push_back(u(rng), u(rng), 0.3f * u(rng));
    tree.insertPointCloud(cloud, octomap::point3d(0.4f * s, 0.1f, 0.2f));
  }
  tree.prune();
  std::ostringstream bt;
  ASSERT_TRUE(tree.writeBinaryConst(bt));
  const BtTree parsed = parseBt(bt.str());
  const OccupancyParams occupancy;
  const MapBlocks blocks = blocksFromLeaves(leavesOf(parsed, occupancy), occupancy, FusionParams{}, 1'000'000);
  const auto map = mapFromBlocks(parsed.resolution_m, blocks);
  expectSameCells(*map, tree);
  // Fusion merged OctoMap's small leaves: fewer cuboids than leaves.
  EXPECT_LT(map->stats().cuboids, tree.getNumLeafNodes());
  // The same as the cell-by-cell import.
  const auto reference = mapFromBt(parsed);
  EXPECT_EQ(map->stats().known_cells, reference->stats().known_cells);
  EXPECT_EQ(map->stats().occupied_cells, reference->stats().occupied_cells);
}

TEST(OctomapInterop, BlocksFromLeavesClampValuesAndFillWholeBlocks) {
  OccupancyParams occupancy;
  // A 32-cell free leaf (8 blocks) and one occupied cell beyond the clamp.
  const std::vector<OctreeLeaf> leaves{{{-32, 0, 0}, 32, -7.0f}, {{40, 3, 5}, 1, 9.0f}};
  const MapBlocks blocks = blocksFromLeaves(leaves, occupancy, FusionParams{}, 9);
  EXPECT_EQ(blocks.size(), 9u);
  const auto map = mapFromBlocks(0.1, blocks);
  EXPECT_EQ(map->stats().known_cells, 32u * 32 * 32 + 1);
  EXPECT_FLOAT_EQ(map->queryCell({-1, 31, 31}).log_odds, occupancy.clamp_min_log_odds);
  EXPECT_EQ(map->queryCell({40, 3, 5}).state, CellState::kOccupied);
  EXPECT_FLOAT_EQ(map->queryCell({40, 3, 5}).log_odds, occupancy.clamp_max_log_odds);
  EXPECT_EQ(map->queryCell({0, 0, 0}).state, CellState::kUnknown);
}

TEST(OctomapInterop, BlocksFromLeavesRefuseTooManyBlocksAndBadLeaves) {
  const OccupancyParams occupancy;
  // The root as one leaf: 4096³ blocks, refused before any is made.
  const std::vector<OctreeLeaf> root{{{-32768, -32768, -32768}, 65536, -1.0f}};
  try {
    blocksFromLeaves(root, occupancy, FusionParams{}, 1'000'000);
    ADD_FAILURE() << "a tree of 4096³ blocks was accepted";
  } catch (const std::length_error& e) {
    EXPECT_NE(std::string(e.what()).find("68719476736 blocks"), std::string::npos) << e.what();
  }
  const std::vector<OctreeLeaf> small{{{0, 0, 0}, 16, 1.0f}, {{16, 0, 0}, 16, 1.0f}};
  EXPECT_THROW(blocksFromLeaves(small, occupancy, FusionParams{}, 1), std::length_error);
  EXPECT_EQ(blocksFromLeaves(small, occupancy, FusionParams{}, 2).size(), 2u);
  for (const OctreeLeaf& bad : {OctreeLeaf{{1, 0, 0}, 2, 0.5f}, OctreeLeaf{{0, 0, 0}, 3, 0.5f},
                                OctreeLeaf{{32767, 0, 0}, 2, 0.5f}, OctreeLeaf{{0, 0, 0}, 0, 0.5f}}) {
    EXPECT_THROW(blocksFromLeaves(std::vector<OctreeLeaf>{bad}, occupancy, FusionParams{}, 10), std::invalid_argument);
  }
}

}  // namespace
}  // namespace rmap::map3d
