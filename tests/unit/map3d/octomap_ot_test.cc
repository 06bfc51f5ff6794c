#include "map3d/octomap_ot.h"

#include <gtest/gtest.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <limits>
#include <random>
#include <sstream>
#include <tuple>

namespace rmap::map3d {
namespace {

using OtLeafTuple = std::tuple<int32_t, int32_t, int32_t, int32_t, float>;

/// A small scene: a few scans into an OctoMap tree of type Tree, pruned.
template <typename Tree>
void fillTree(Tree& tree) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f);
  for (int s = 0; s < 3; ++s) {
    octomap::Pointcloud cloud;
    for (int i = 0; i < 1500; ++i) cloud.push_back(u(rng), u(rng), 0.4f * u(rng));
    tree.insertPointCloud(cloud, octomap::point3d(0.3f * s, 0.0f, 0.2f));
  }
  tree.updateInnerOccupancy();
  tree.prune();
}

template <typename Tree>
std::vector<OtLeafTuple> octomapLeaves(const Tree& tree) {
  std::vector<OtLeafTuple> out;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    const int size = 1 << (16 - it.getDepth());
    const octomap::OcTreeKey k = it.getKey();
    out.emplace_back((k[0] & ~(size - 1)) - 32768, (k[1] & ~(size - 1)) - 32768, (k[2] & ~(size - 1)) - 32768, size,
                     it->getLogOdds());
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<OtLeafTuple> parsedLeaves(const OtTree& tree) {
  std::vector<OtLeafTuple> out;
  for (const OctreeLeaf& l : tree.leaves) {
    out.emplace_back(l.min_cell.x, l.min_cell.y, l.min_cell.z, l.size_cells, l.log_odds);
  }
  std::sort(out.begin(), out.end());
  return out;
}

template <typename Tree>
std::string written(const Tree& tree) {
  std::ostringstream out;
  EXPECT_TRUE(tree.write(out));
  return out.str();
}

TEST(OctomapOt, ParsesAnOcTreeWithItsLogOdds) {
  octomap::OcTree tree(0.05);
  fillTree(tree);
  const std::string bytes = written(tree);
  ASSERT_TRUE(looksLikeOt(bytes));
  const OtTree parsed = parseOt(bytes);
  EXPECT_EQ(parsed.id, "OcTree");
  EXPECT_DOUBLE_EQ(parsed.resolution_m, 0.05);
  const std::vector<OtLeafTuple> expected = octomapLeaves(tree);
  ASSERT_GT(expected.size(), 1000u);
  EXPECT_EQ(parsedLeaves(parsed), expected);
}

TEST(OctomapOt, ParsesAColorOcTreeIgnoringColours) {
  octomap::ColorOcTree tree(0.1);
  fillTree(tree);
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) it->setColor(200, 10, 30);
  const OtTree parsed = parseOt(written(tree));
  EXPECT_EQ(parsed.id, "ColorOcTree");
  EXPECT_EQ(parsedLeaves(parsed), octomapLeaves(tree));
}

TEST(OctomapOt, EmptyTree) {
  const OtTree parsed = parseOt(written(octomap::OcTree(0.2)));
  EXPECT_DOUBLE_EQ(parsed.resolution_m, 0.2);
  EXPECT_TRUE(parsed.leaves.empty());
}

void expectOtRejected(const std::string& bytes, const std::string& message_part) {
  try {
    parseOt(bytes);
    ADD_FAILURE() << "accepted input; expected an error containing \"" << message_part << "\"";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(message_part), std::string::npos) << e.what();
  }
}

TEST(OctomapOt, RejectsBadInput) {
  octomap::OcTree tree(0.1);
  fillTree(tree);
  const std::string good = written(tree);
  const size_t data_at = good.find("data\n") + 5;
  for (size_t cut : {data_at, data_at + 3, (data_at + good.size()) / 2, good.size() - 1}) {
    expectOtRejected(good.substr(0, cut), "truncated data");
  }
  expectOtRejected(good + "x", "trailing bytes");
  std::string wrong_size = good;
  wrong_size.replace(wrong_size.find("size ") + 5, 1, "9");
  expectOtRejected(wrong_size, "nodes but the header says size");
  expectOtRejected("# Octomap OcTree binary file\nid OcTree\nsize 0\nres 0.1\ndata\n", "first line");
  expectOtRejected("# Octomap OcTree file\nid CountingOcTree\nsize 0\nres 0.1\ndata\n", "unsupported tree id");
  expectOtRejected("# Octomap OcTree file\nid OcTree\nsize 0\nres 0\ndata\n", "res must be");
  // A leaf whose value is NaN.
  std::string nan_leaf = "# Octomap OcTree file\nid OcTree\nsize 1\nres 0.1\ndata\n";
  const float nan = std::numeric_limits<float>::quiet_NaN();
  nan_leaf.append(reinterpret_cast<const char*>(&nan), sizeof nan);
  nan_leaf += '\0';
  expectOtRejected(nan_leaf, "not finite");
  // A chain of nodes (child 0 only) one level too deep.
  std::string deep = "# Octomap OcTree file\nid OcTree\nsize 18\nres 0.1\ndata\n";
  const float zero = 0.0f;
  for (int depth = 0; depth <= 16; ++depth) {
    deep.append(reinterpret_cast<const char*>(&zero), sizeof zero);
    deep += '\x01';
  }
  expectOtRejected(deep, "depth 16");
}

}  // namespace
}  // namespace rmap::map3d
