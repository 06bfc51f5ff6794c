// `rmap import` against a real rmapd: OctoMap trees made by liboctomap (.bt and .ot) become
// maps whose occupancy answers equal OctoMap's, survive kill -9, and bad imports (malformed
// file, non-empty map without --replace, too large, wrong role) are refused changing nothing.
#include <gtest/gtest.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <fstream>
#include <random>

#include "api_helpers.h"
#include "rmap_cli.h"
#include "rmapd_process.h"

namespace rmap::testing {
namespace {

/// Three scans of random points around the origin, like a small room.
template <typename Tree>
void fillTree(Tree& tree, uint64_t seed) {
  std::mt19937 rng(static_cast<uint32_t>(seed));
  std::uniform_real_distribution<float> u(-3.0f, 3.0f);
  for (int s = 0; s < 3; ++s) {
    octomap::Pointcloud cloud;
    for (int i = 0; i < 2000; ++i) cloud.push_back(u(rng), u(rng), 0.5f * u(rng));
    tree.insertPointCloud(cloud, octomap::point3d(0.3f * s, 0.0f, 0.1f));
  }
  tree.updateInnerOccupancy();
  tree.prune();
}

/// Leaf corner cells of the tree and random cell centres around it (unknown space too).
template <typename Tree>
std::vector<Eigen::Vector3d> samplePoints(const Tree& tree) {
  const double r = tree.getResolution();
  std::vector<Eigen::Vector3d> points;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    const double half = it.getSize() / 2;
    points.emplace_back(it.getX() - half + r / 2, it.getY() - half + r / 2, it.getZ() - half + r / 2);
  }
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  for (int i = 0; i < 2000; ++i) {
    points.emplace_back((std::floor(u(rng) / r) + 0.5) * r, (std::floor(u(rng) / r) + 0.5) * r,
                        (std::floor(u(rng) / r) + 0.5) * r);
  }
  return points;
}

/// Server states equal OctoMap's at every point; returns how many were occupied.
template <typename Tree>
size_t expectSameOccupancy(client::HttpClient& http, const std::string& map, const Tree& tree,
                           const std::vector<Eigen::Vector3d>& points, double probability_tolerance) {
  const v1::OccupancyBatchResponse answers = batchQuery(http, map, points);
  size_t occupied = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const auto* node = tree.search(points[i].x(), points[i].y(), points[i].z());
    const v1::CellState expected = !node ? v1::UNKNOWN : tree.isNodeOccupied(node) ? v1::OCCUPIED : v1::FREE;
    EXPECT_EQ(answers.states(static_cast<int>(i)), expected) << "point " << points[i].transpose();
    if (node && probability_tolerance > 0) {
      EXPECT_NEAR(answers.probabilities(static_cast<int>(i)), node->getOccupancy(), probability_tolerance);
    }
    occupied += expected == v1::OCCUPIED;
    if (::testing::Test::HasFailure()) break;
  }
  return occupied;
}

class Import : public ::testing::Test {
 protected:
  std::string importArgs(const RmapdProcess& rmapd, const std::string& map, const std::filesystem::path& file) const {
    return "import --server " + rmapd.httpUrl() + " --map " + map + " '" + file.string() + "'";
  }
  TempDir dir_{"rmap-import"};
};

TEST_F(Import, BtBecomesAMapWithOctomapsOccupancyAndSurvivesKill9) {
  octomap::OcTree tree(0.1);
  fillTree(tree, 1);
  const std::filesystem::path file = dir_.path() / "room.bt";
  ASSERT_TRUE(tree.writeBinary(file.string()));
  const std::vector<Eigen::Vector3d> points = samplePoints(tree);
  uint64_t cuboids = 0;
  {
    RmapdProcess rmapd(dir_.path() / "data");
    const CliRun run = runRmap(importArgs(rmapd, "room", file), dir_.path());
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_NE(run.out.find("into new map room"), std::string::npos) << run.out;
    client::HttpClient http(rmapd.httpUrl());
    const nlohmann::json info = getJson(http, "/v1/maps/room");
    EXPECT_DOUBLE_EQ(info["resolution_m"].get<double>(), 0.1);
    cuboids = info["cuboids"].get<uint64_t>();
    EXPECT_LT(cuboids, tree.getNumLeafNodes());  // fused
    const size_t occupied = expectSameOccupancy(http, "room", tree, points, 0.0);
    EXPECT_GT(occupied, 100u);
    std::printf("[ import bt ] %zu leaves -> %lu cuboids; %zu points agree (%zu occupied)\n", tree.getNumLeafNodes(),
                static_cast<unsigned long>(cuboids), points.size(), occupied);
    // The answer came after the import was durable: a crash right now loses nothing.
    rmapd.kill9();
  }
  RmapdProcess rmapd(dir_.path() / "data");
  client::HttpClient http(rmapd.httpUrl());
  EXPECT_EQ(getJson(http, "/v1/maps/room")["cuboids"].get<uint64_t>(), cuboids);
  expectSameOccupancy(http, "room", tree, points, 0.0);
}

TEST_F(Import, OtKeepsProbabilitiesAndReplaceIsExplicit) {
  RmapdProcess rmapd(dir_.path() / "data");
  client::HttpClient http(rmapd.httpUrl());
  octomap::OcTree first(0.05);
  fillTree(first, 2);
  const std::filesystem::path first_file = dir_.path() / "first.ot";
  ASSERT_TRUE(first.write(first_file.string()));
  ASSERT_EQ(runRmap(importArgs(rmapd, "lab", first_file), dir_.path()).exit_code, 0);
  // Fusion moves a cell's log-odds by at most half the tolerance (0.125): a few hundredths in probability.
  expectSameOccupancy(http, "lab", first, samplePoints(first), 0.04);
  const nlohmann::json before = getJson(http, "/v1/maps/lab");

  // A second tree, a ColorOcTree: refused without --replace, the map unchanged.
  octomap::ColorOcTree second(0.05);
  fillTree(second, 3);
  const std::filesystem::path second_file = dir_.path() / "second.ot";
  ASSERT_TRUE(second.write(second_file.string()));
  CliRun run = runRmap(importArgs(rmapd, "lab", second_file), dir_.path());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("map_not_empty"), std::string::npos) << run.err;
  EXPECT_EQ(getJson(http, "/v1/maps/lab")["known_cells"], before["known_cells"]);
  EXPECT_EQ(getJson(http, "/v1/maps/lab")["version"], before["version"]);

  run = runRmap(importArgs(rmapd, "lab", second_file) + " --replace", dir_.path());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  expectSameOccupancy(http, "lab", second, samplePoints(second), 0.04);
  // Nothing of the first tree is left where the second knows nothing.
  expectSameOccupancy(http, "lab", second, samplePoints(first), 0.0);

  // Another resolution does not go into an existing map.
  octomap::OcTree coarse(0.2);
  fillTree(coarse, 4);
  const std::filesystem::path coarse_file = dir_.path() / "coarse.bt";
  ASSERT_TRUE(coarse.writeBinary(coarse_file.string()));
  run = runRmap(importArgs(rmapd, "lab", coarse_file) + " --replace", dir_.path());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("resolution_mismatch"), std::string::npos) << run.err;
}

TEST_F(Import, MalformedAndTooLargeFilesAreRefusedChangingNothing) {
  RmapdProcess rmapd(dir_.path() / "data", "limits:\n  max_import_blocks: 100000\n");
  client::HttpClient http(rmapd.httpUrl());
  octomap::OcTree tree(0.1);
  fillTree(tree, 5);
  std::ostringstream bytes;
  ASSERT_TRUE(tree.writeBinary(bytes));
  const std::string good = bytes.str();
  const std::filesystem::path file = dir_.path() / "bad.bt";
  // Truncated, a trailing byte, not an OctoMap at all.
  for (const std::string& bad : {good.substr(0, good.size() / 2), good + "x", std::string("hello\n")}) {
    writeFile(file, bad);
    const CliRun run = runRmap(importArgs(rmapd, "fresh", file), dir_.path());
    EXPECT_EQ(run.exit_code, 1);
    EXPECT_NE(run.err.find("invalid_argument"), std::string::npos) << run.err;
  }
  // One free leaf of 32768³ cells (a child of the root): more blocks than the limit.
  writeFile(file, std::string("# Octomap OcTree binary file\nid OcTree\nsize 2\nres 0.1\ndata\n") + '\x01' + '\x00');
  const CliRun run = runRmap(importArgs(rmapd, "fresh", file), dir_.path());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("import_too_large"), std::string::npos) << run.err;
  // None of them made the map.
  EXPECT_EQ(http.get("/v1/maps/fresh").status, 404);
}

TEST_F(Import, OnlyAdminsImportAndTheBodyLimitHolds) {
  RmapdProcess rmapd(dir_.path() / "data",
                     std::string(kRoleTokensYaml) + "limits:\n  max_body_bytes: 16384\n  max_batch_points: 500\n");
  octomap::OcTree tree(0.1);
  fillTree(tree, 6);
  const std::filesystem::path small = dir_.path() / "small.bt", large = dir_.path() / "large.bt";
  // A corner of the tree fits the body limit; the whole tree with free space does not.
  octomap::OcTree corner(0.1);
  corner.updateNode(octomap::point3d(0.05f, 0.05f, 0.05f), true);
  ASSERT_TRUE(corner.writeBinary(small.string()));
  ASSERT_TRUE(tree.writeBinary(large.string()));
  ASSERT_GT(std::filesystem::file_size(large), 16384u);
  for (const char* token : {"viewer-token-1", "robot-token-1"}) {
    const CliRun run = runRmap(importArgs(rmapd, "m", small) + " --token " + token, dir_.path());
    EXPECT_EQ(run.exit_code, 1);
    EXPECT_NE(run.err.find("permission_denied"), std::string::npos) << run.err;
  }
  CliRun run = runRmap(importArgs(rmapd, "m", large) + " --token admin-token-1", dir_.path());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("payload_too_large"), std::string::npos) << run.err;
  run = runRmap(importArgs(rmapd, "m", small) + " --token admin-token-1", dir_.path());
  EXPECT_EQ(run.exit_code, 0) << run.err;
  client::HttpClient http(rmapd.httpUrl(), "viewer-token-1");
  EXPECT_EQ(getJson(http, "/v1/maps/m")["occupied_cells"].get<int>(), 1);
}

}  // namespace
}  // namespace rmap::testing
