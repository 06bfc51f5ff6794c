#include "map3d/octomap_bt.h"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

namespace rmap::map3d {
namespace {

const std::string kGebPath = std::string(RMAP_SHARED_DATA_DIR) + "/octomap/geb079.bt";

/// Comparable form of a leaf: min cell, edge in cells, state.
using BtLeafTuple = std::tuple<int32_t, int32_t, int32_t, int32_t, bool>;

std::vector<BtLeafTuple> sortedLeaves(const std::vector<BtLeaf>& leaves) {
  std::vector<BtLeafTuple> out;
  out.reserve(leaves.size());
  for (const BtLeaf& l : leaves) out.emplace_back(l.min_cell.x, l.min_cell.y, l.min_cell.z, l.size_cells, l.occupied);
  std::sort(out.begin(), out.end());
  return out;
}

/// Leaves of an OctoMap tree in the same form (keys shifted to cell indices).
std::vector<BtLeafTuple> sortedLeaves(const octomap::OcTree& tree) {
  std::vector<BtLeafTuple> out;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const int32_t size = int32_t{1} << (16 - it.getDepth());
    // The iterator's key is the cube's centre key; clearing the low bits gives its corner.
    const octomap::OcTreeKey k = it.getKey();
    auto corner = [&](int a) { return static_cast<int32_t>(k[a] & ~(size - 1)) - 32768; };
    out.emplace_back(corner(0), corner(1), corner(2), size, tree.isNodeOccupied(*it));
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// Reads with liboctomap; its readBinary also checks the node count against `size`.
std::unique_ptr<octomap::OcTree> readWithOctomap(const std::string& bytes) {
  auto tree = std::make_unique<octomap::OcTree>(0.1);
  std::istringstream in(bytes);
  EXPECT_TRUE(tree->readBinary(in));
  return tree;
}

octomap::OcTreeKey octoKey(const CellKey& c) {
  return octomap::OcTreeKey(static_cast<octomap::key_type>(c.x + 32768), static_cast<octomap::key_type>(c.y + 32768),
                            static_cast<octomap::key_type>(c.z + 32768));
}

/// Every base cell of the leaves, sorted (x, y, z).
std::vector<std::tuple<int32_t, int32_t, int32_t, bool>> expand(const std::vector<BtLeaf>& leaves) {
  std::vector<std::tuple<int32_t, int32_t, int32_t, bool>> out;
  for (const BtLeaf& l : leaves) {
    for (int32_t z = 0; z < l.size_cells; ++z)
      for (int32_t y = 0; y < l.size_cells; ++y)
        for (int32_t x = 0; x < l.size_cells; ++x)
          out.emplace_back(l.min_cell.x + x, l.min_cell.y + y, l.min_cell.z + z, l.occupied);
  }
  std::sort(out.begin(), out.end());
  return out;
}

/// Hand-made cells: a full free 2×2×2 octant, a full occupied octant at
/// negative indices, a mixed octant, lone cells and the extreme corners.
std::vector<BtCell> handMadeCells() {
  std::vector<BtCell> cells;
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 2; ++x) {
        cells.push_back({{4 + x, 6 + y, 8 + z}, false});
        cells.push_back({{-8 + x, -2 + y, -4 + z}, true});
        cells.push_back({{10 + x, 10 + y, 10 + z}, (x + y + z) % 2 == 0});
      }
  cells.push_back({{-32768, -32768, -32768}, true});
  cells.push_back({{32767, 32767, 32767}, false});
  cells.push_back({{-32768, 32767, 0}, true});
  cells.push_back({{-1, -1, -1}, false});
  cells.push_back({{0, 0, 0}, true});
  cells.push_back({{7, -300, 12000}, true});
  return cells;
}

TEST(OctomapBt, ParsesGeb079LikeOctomap) {
  if (!std::filesystem::exists(kGebPath)) GTEST_SKIP() << kGebPath << " absent (shared data not available)";
  const BtTree parsed = parseBt(readBytes(kGebPath));
  EXPECT_DOUBLE_EQ(parsed.resolution_m, 0.08);

  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(kGebPath));
  const auto expected = sortedLeaves(tree);
  const auto got = sortedLeaves(parsed.leaves);
  ASSERT_EQ(got.size(), expected.size());
  const auto occupied = [](const auto& v) {
    return std::count_if(v.begin(), v.end(), [](const BtLeafTuple& t) { return std::get<4>(t); });
  };
  EXPECT_EQ(occupied(got), occupied(expected));
  EXPECT_EQ(got.size() - occupied(got), expected.size() - occupied(expected));
  EXPECT_TRUE(got == expected);
}

TEST(OctomapBt, LeavesComeInDepthFirstMortonOrder) {
  const BtTree t = parseBt(writeBt(0.05, handMadeCells()));
  // Depth-first order visits octants in child order: x, then y, then z bit.
  auto morton_less = [](const BtLeaf& a, const BtLeaf& b) {
    for (int bit = 15; bit >= 0; --bit) {
      for (int axis = 2; axis >= 0; --axis) {
        const int ba = ((a.min_cell[axis] + 32768) >> bit) & 1, bb = ((b.min_cell[axis] + 32768) >> bit) & 1;
        if (ba != bb) return ba < bb;
      }
    }
    return false;
  };
  EXPECT_TRUE(std::is_sorted(t.leaves.begin(), t.leaves.end(), morton_less));
}

TEST(OctomapBt, WrittenCellsReadBackByOctomap) {
  const std::vector<BtCell> cells = handMadeCells();
  const std::string bytes = writeBt(0.05, cells);
  const auto tree_ptr = readWithOctomap(bytes);
  const octomap::OcTree& tree = *tree_ptr;
  EXPECT_DOUBLE_EQ(tree.getResolution(), 0.05);
  for (const BtCell& c : cells) {
    const octomap::OcTreeNode* node = tree.search(octoKey(c.cell));
    ASSERT_NE(node, nullptr) << c.cell.x << " " << c.cell.y << " " << c.cell.z;
    EXPECT_EQ(tree.isNodeOccupied(node), c.occupied) << c.cell.x << " " << c.cell.y << " " << c.cell.z;
  }
  // No extra leaves: the leaves' volumes add up to the input cells exactly.
  uint64_t leaf_cells = 0;
  for (const auto& l : sortedLeaves(tree)) leaf_cells += uint64_t(std::get<3>(l)) * std::get<3>(l) * std::get<3>(l);
  EXPECT_EQ(leaf_cells, cells.size());
  // The two uniform octants are pruned into 2-cell leaves, the mixed one is not.
  const auto leaves = sortedLeaves(tree);
  EXPECT_EQ(std::count(leaves.begin(), leaves.end(), BtLeafTuple{4, 6, 8, 2, false}), 1);
  EXPECT_EQ(std::count(leaves.begin(), leaves.end(), BtLeafTuple{-8, -2, -4, 2, true}), 1);
  EXPECT_EQ(std::count_if(leaves.begin(), leaves.end(), [](const BtLeafTuple& l) { return std::get<3>(l) > 2; }), 0);
  EXPECT_EQ(leaves.size(), 2u + 8u + 6u);
}

TEST(OctomapBt, PrunesLargeUniformOctants) {
  std::vector<BtCell> cells;
  for (int z = 0; z < 16; ++z)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) cells.push_back({{-16 + x, 32 + y, z}, true});
  const BtTree t = parseBt(writeBt(0.1, cells));
  ASSERT_EQ(t.leaves.size(), 1u);
  EXPECT_EQ(t.leaves[0].min_cell, (CellKey{-16, 32, 0}));
  EXPECT_EQ(t.leaves[0].size_cells, 16);
  EXPECT_TRUE(t.leaves[0].occupied);
}

TEST(OctomapBt, RoundTripKeepsCells) {
  std::vector<BtCell> cells = handMadeCells();
  const BtTree t = parseBt(writeBt(0.2, cells));
  EXPECT_DOUBLE_EQ(t.resolution_m, 0.2);
  std::vector<std::tuple<int32_t, int32_t, int32_t, bool>> expected;
  for (const BtCell& c : cells) expected.emplace_back(c.cell.x, c.cell.y, c.cell.z, c.occupied);
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(expand(t.leaves), expected);
}

TEST(OctomapBt, DuplicateCellsLastWins) {
  const BtTree t = parseBt(writeBt(0.1, {{{1, 2, 3}, true}, {{5, 5, 5}, true}, {{1, 2, 3}, false}}));
  ASSERT_EQ(t.leaves.size(), 2u);
  EXPECT_EQ(expand(t.leaves), (std::vector<std::tuple<int32_t, int32_t, int32_t, bool>>{{1, 2, 3, false},
                                                                                       {5, 5, 5, true}}));
}

TEST(OctomapBt, EmptyTreeIsValidForOctomap) {
  const std::string bytes = writeBt(0.1, {});
  EXPECT_NE(bytes.find("\nsize 0\n"), std::string::npos);
  EXPECT_TRUE(parseBt(bytes).leaves.empty());
  EXPECT_EQ(readWithOctomap(bytes)->size(), 0u);
}

TEST(OctomapBt, HeaderInAnyOrderWithComments) {
  const std::string data = writeBt(0.25, {{{0, 0, 0}, true}});
  const std::string body = data.substr(data.find("data\n") + 5);
  const std::string bytes = "# Octomap OcTree binary file, extra words\n# a comment\nres 0.25\n#x\nsize " +
                            std::to_string(parseBt(data).leaves.size() + 16) + "\nfoo bar\nid OcTree\ndata\n" + body;
  const BtTree t = parseBt(bytes);
  EXPECT_DOUBLE_EQ(t.resolution_m, 0.25);
  ASSERT_EQ(t.leaves.size(), 1u);
  EXPECT_EQ(t.leaves[0].min_cell, (CellKey{0, 0, 0}));
  EXPECT_EQ(t.leaves[0].size_cells, 1);
  EXPECT_EQ(readWithOctomap(bytes)->size(), 17u);  // OctoMap agrees on the header and the node count
}

TEST(OctomapBt, Geb079RewrittenGivesSameLeaves) {
  if (!std::filesystem::exists(kGebPath)) GTEST_SKIP() << kGebPath << " absent (shared data not available)";
  const BtTree parsed = parseBt(readBytes(kGebPath));
  std::vector<BtCell> cells;
  for (const BtLeaf& l : parsed.leaves) {
    for (int32_t z = 0; z < l.size_cells; ++z)
      for (int32_t y = 0; y < l.size_cells; ++y)
        for (int32_t x = 0; x < l.size_cells; ++x)
          cells.push_back({{l.min_cell.x + x, l.min_cell.y + y, l.min_cell.z + z}, l.occupied});
  }
  const std::string bytes = writeBt(parsed.resolution_m, std::move(cells));
  // OctoMap wrote the fixture pruned and depth first, so even the bytes agree.
  const std::string original_bytes = readBytes(kGebPath);
  EXPECT_TRUE(bytes.substr(bytes.find("\ndata\n")) == original_bytes.substr(original_bytes.find("\ndata\n")));
  octomap::OcTree original(0.1);
  ASSERT_TRUE(original.readBinary(kGebPath));
  const auto rewritten = readWithOctomap(bytes);
  EXPECT_TRUE(sortedLeaves(*rewritten) == sortedLeaves(original));
  EXPECT_EQ(rewritten->size(), original.size());
}

void expectBtRejected(const std::string& bytes, const std::string& message_part) {
  try {
    parseBt(bytes);
    ADD_FAILURE() << "accepted input; expected an error containing \"" << message_part << "\"";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(message_part), std::string::npos) << e.what();
  }
}

std::string header(const std::string& lines) { return "# Octomap OcTree binary file\n" + lines; }

TEST(OctomapBt, RejectsBadHeaders) {
  expectBtRejected("", "first line");
  expectBtRejected("# Octomap OcTree file\nid OcTree\nsize 0\nres 0.1\ndata\n", "first line");
  expectBtRejected(header("id ColorOcTree\nsize 0\nres 0.1\ndata\n"), "unsupported tree id");
  expectBtRejected(header("size 0\nres 0.1\ndata\n"), "no id");
  expectBtRejected(header("id OcTree\nsize 0\ndata\n"), "no res");
  expectBtRejected(header("id OcTree\nsize 0\nres -0.1\ndata\n"), "res must be");
  expectBtRejected(header("id OcTree\nsize 0\nres 0\ndata\n"), "res must be");
  expectBtRejected(header("id OcTree\nsize 0\nres inf\ndata\n"), "res must be");
  expectBtRejected(header("id OcTree\nsize 0\nres nan\ndata\n"), "res must be");
  expectBtRejected(header("id OcTree\nsize 0\nres 0.1x\ndata\n"), "bad res");
  expectBtRejected(header("id OcTree\nres 0.1\ndata\n"), "no size");
  expectBtRejected(header("id OcTree\nsize -3\nres 0.1\ndata\n"), "bad size");
  expectBtRejected(header("id OcTree\nsize 0\nres 0.1\n"), "before the \"data\"");
  expectBtRejected(header("id OcTree\nsize 0\nres 0.1\ndata\nxx"), "after a header with size 0");
}

TEST(OctomapBt, RejectsBadData) {
  const std::string good = writeBt(0.1, handMadeCells());
  const size_t data_at = good.find("data\n") + 5;
  ASSERT_LT(data_at + 4, good.size());
  for (size_t cut : {data_at, data_at + 1, data_at + 2, (data_at + good.size()) / 2, good.size() - 1}) {
    expectBtRejected(good.substr(0, cut), "truncated data");
  }
  expectBtRejected(good + "\n", "trailing bytes");
  std::string wrong_size = good;
  wrong_size.replace(wrong_size.find("size ") + 5, 1, "9");
  expectBtRejected(wrong_size, "nodes but the header says size");
  // A chain of inner nodes (child 0 only) one level too deep.
  std::string deep = header("id OcTree\nsize 17\nres 0.1\ndata\n");
  for (int depth = 0; depth < 16; ++depth) deep += std::string("\x03\x00", 2);
  expectBtRejected(deep, "depth 16");
}

TEST(OctomapBt, RejectsTruncatedGeb079) {
  if (!std::filesystem::exists(kGebPath)) GTEST_SKIP() << kGebPath << " absent (shared data not available)";
  const std::string bytes = readBytes(kGebPath);
  for (size_t cut : {size_t{5}, size_t{150}, size_t{200}, bytes.size() / 3, bytes.size() / 2, bytes.size() - 2,
                     bytes.size() - 1}) {
    EXPECT_THROW(parseBt(bytes.substr(0, cut)), std::runtime_error) << "cut at " << cut;
  }
  EXPECT_THROW(parseBt(bytes + std::string(2, '\0')), std::runtime_error);
}

TEST(OctomapBt, WriteRejectsBadArguments) {
  EXPECT_THROW(writeBt(0.1, {{{32768, 0, 0}, true}}), std::invalid_argument);
  EXPECT_THROW(writeBt(0.1, {{{0, -32769, 0}, true}}), std::invalid_argument);
  EXPECT_THROW(writeBt(0.0, {{{0, 0, 0}, true}}), std::invalid_argument);
  EXPECT_THROW(writeBt(std::nan(""), {}), std::invalid_argument);
  try {
    writeBt(0.1, {{{1, 2, 40000}, true}});
    ADD_FAILURE() << "accepted an out-of-range cell";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("(1, 2, 40000)"), std::string::npos) << e.what();
  }
}

TEST(OctomapBt, CubesWriteTheTreeTheirCellsWrite) {
  // Eight 2-cell cubes of one state fill a 4-cell octant, which is pruned; a free cube beside it.
  std::vector<BtLeaf> cubes;
  std::vector<BtCell> cells;
  for (int i = 0; i < 8; ++i) {
    const CellKey min{(i & 1) * 2, (i & 2), (i & 4) / 2};
    cubes.push_back({min, 2, true});
    for (int k = 0; k < 8; ++k) cells.push_back({{min.x + (k & 1), min.y + ((k >> 1) & 1), min.z + (k >> 2)}, true});
  }
  cubes.push_back({{-8, -8, -8}, 8, false});
  for (int z = -8; z < 0; ++z) {
    for (int y = -8; y < 0; ++y) {
      for (int x = -8; x < 0; ++x) cells.push_back({{x, y, z}, false});
    }
  }
  const std::string bytes = writeBtCubes(0.1, cubes);
  EXPECT_EQ(bytes, writeBt(0.1, cells));
  const auto tree = readWithOctomap(bytes);
  EXPECT_TRUE(tree->isNodeOccupied(tree->search(octoKey({3, 3, 3}))));
  EXPECT_FALSE(tree->isNodeOccupied(tree->search(octoKey({-8, -1, -5}))));
  EXPECT_EQ(tree->search(octoKey({4, 0, 0})), nullptr);
  for (const BtLeaf& bad : {BtLeaf{{1, 0, 0}, 2, true}, BtLeaf{{0, 0, 0}, 3, true}, BtLeaf{{0, 0, 0}, 65536, true}}) {
    EXPECT_THROW(writeBtCubes(0.1, {bad}), std::invalid_argument);
  }
}

}  // namespace
}  // namespace rmap::map3d
