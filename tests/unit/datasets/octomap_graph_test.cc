#include "datasets/octomap_graph.h"

#include <gtest/gtest.h>
#include <octomap/ScanGraph.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "dataset_test_support.h"

namespace rmap::datasets {
namespace {

/// A two-node graph with an edge, written by liboctomap itself.
std::string octomapWrittenGraph() {
  octomap::ScanGraph graph;
  auto* a = new octomap::Pointcloud();
  a->push_back(1.0f, 2.0f, 3.0f);
  a->push_back(-0.5f, 0.25f, 4.0f);
  auto* b = new octomap::Pointcloud();
  b->push_back(7.0f, 8.0f, 9.0f);
  octomap::ScanNode* na = graph.addNode(a, octomap::pose6d(0.5, -1.0, 2.0, 0.1, -0.2, 0.3));
  octomap::ScanNode* nb = graph.addNode(b, octomap::pose6d(3.0, 4.0, 5.0, 0.0, 0.0, 1.2));
  graph.addEdge(na, nb, octomap::pose6d(2.5, 5.0, 3.0, 0.0, 0.0, 0.9));
  std::ostringstream out;
  graph.writeBinary(out);
  return out.str();
}

TEST(OctomapGraph, ReadsWhatLiboctomapWrites) {
  const std::vector<GraphScan> scans = parseOctomapGraph(octomapWrittenGraph(), "t.graph");
  ASSERT_EQ(scans.size(), 2u);
  ASSERT_EQ(scans[0].points_m.size(), 2u);
  EXPECT_EQ(scans[0].points_m[0], Eigen::Vector3f(1.0f, 2.0f, 3.0f));
  EXPECT_EQ(scans[0].points_m[1], Eigen::Vector3f(-0.5f, 0.25f, 4.0f));
  ASSERT_EQ(scans[1].points_m.size(), 1u);
  EXPECT_EQ(scans[1].id, 1u);
  // The pose as octomath places points: the world point of a scan point must match.
  const octomap::pose6d pose(0.5, -1.0, 2.0, 0.1, -0.2, 0.3);
  const octomap::point3d expected = pose.transform(octomap::point3d(1.0f, 2.0f, 3.0f));
  const Eigen::Vector3d got = scans[0].sensor_pose * Eigen::Vector3d(1.0, 2.0, 3.0);
  EXPECT_NEAR(got.x(), expected.x(), 1e-5);
  EXPECT_NEAR(got.y(), expected.y(), 1e-5);
  EXPECT_NEAR(got.z(), expected.z(), 1e-5);
  EXPECT_NEAR(scans[1].sensor_pose.translation().x(), 3.0, 1e-6);
}

TEST(OctomapGraph, LiboctomapReadsTheSameNodes) {
  const std::string bytes = octomapWrittenGraph();
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "rmap_octomap_graph_test.graph";
  std::ofstream(file, std::ios::binary) << bytes;
  octomap::ScanGraph graph;
  graph.readBinary(file.string());
  std::filesystem::remove(file);
  const std::vector<GraphScan> scans = parseOctomapGraph(bytes, "t.graph");
  ASSERT_EQ(graph.size(), scans.size());
  for (size_t i = 0; i < scans.size(); ++i) {
    const octomap::ScanNode& node = **(graph.begin() + static_cast<std::ptrdiff_t>(i));
    ASSERT_EQ(node.scan->size(), scans[i].points_m.size());
    EXPECT_NEAR(node.pose.trans().x(), scans[i].sensor_pose.translation().x(), 1e-6);
    EXPECT_NEAR(node.pose.trans().z(), scans[i].sensor_pose.translation().z(), 1e-6);
  }
}

TEST(OctomapGraph, SharedSphericalScan) {
  const std::string path = std::string(RMAP_SHARED_DATA_DIR) + "/octomap/spherical_scan.graph";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not found";
  const std::vector<GraphScan> scans = readOctomapGraph(path);
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_EQ(scans[0].points_m.size(), 10201u);
  EXPECT_NEAR(scans[0].sensor_pose.translation().x(), 1.0, 1e-9);
  EXPECT_NEAR(scans[0].sensor_pose.translation().z(), -0.5, 1e-9);
}

TEST(OctomapGraph, BadInputNamesTheOffset) {
  const std::string good = octomapWrittenGraph();
  const auto parse = [](const std::string& c) { parseOctomapGraph(c, "t.graph"); };
  expectParseError(parse, good.substr(0, good.size() - 3), "t.graph: offset");
  expectParseError(parse, good.substr(0, 2), "node count is missing");
  expectParseError(parse, good + "x", "1 bytes after the last edge");
  std::string tag = good;
  tag[8] = 4;  // the first point's size tag
  expectParseError(parse, tag, "offset 8: point has size tag 4");
  std::string huge = good;
  huge[4] = '\xff', huge[5] = '\xff', huge[6] = '\xff';  // point count of node 0
  expectParseError(parse, huge, "claims");
}

}  // namespace
}  // namespace rmap::datasets
