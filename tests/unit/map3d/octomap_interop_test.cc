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

TEST(OctomapInterop, ExportIsReadBackByOctomapWithTheSameCells) {
  CuboidMap map(0.05);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f);
  for (int s = 0; s < 3; ++s) {
    std::vector<Eigen::Vector3f> points;
    for (int i = 0; i < 3000; ++i) points.push_back({u(rng), u(rng), u(rng) * 0.3f});
    map.insertScan({0.2f * s, 0.0f, 0.1f}, points);
  }
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

}  // namespace
}  // namespace rmap::map3d
