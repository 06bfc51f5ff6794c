#include "datasets/uos_3dtk.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "dataset_test_support.h"

namespace rmap::datasets {
namespace {

namespace fs = std::filesystem;

/// Points come from centimetres read into floats: 1e-5 m covers their rounding.
void expectPointCm(const Eigen::Vector3f& p, double x, double y, double z) { expectPoint(p, x, y, z, 1e-5); }

class Uos3dtkTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rmap_uos_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  void write(const std::string& name, const std::string& text) const {
    std::ofstream(dir_ / name, std::ios::binary) << text;
  }

  void expectError(const std::string& part) const {
    try {
      readUos3dtk(dir_.string());
      ADD_FAILURE() << "accepted; expected an error containing \"" << part << "\"";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  }

  /// A valid three-scan folder (see ReadsPosesAndConvertsFrames for the values).
  void writeValidFolder() const {
    write("scan000.3d",
          "6 x 1\n"
          "100 0 0\n"
          "10 0 0\n"                // 10 cm: too close
          "0 0 3276\n"              // no return
          "nan 0 0\n"               // non-finite
          "# comment\n"
          "0 200 0 # trailing\r\n");
    write("scan000.pose", "0 0 0\n0 0 0\n");
    write("scan001.3d", "0 0 100\n");
    write("scan001.pose", "999 999 999\n0 0 0\n");  // ignored: .frames wins
    // Second line: rotation of 90° about y (up), translation (100, 0, 200), column-major.
    write("scan001.frames",
          "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1 2\n"
          "0 0 -1 0 0 1 0 0 1 0 0 0 100 0 200 1 1\n");
    write("scan002.3d", "0 0 100\n");
    write("scan002.pose", "100 0 0\n90 90 0\n");
    write("scan004.3d", "1 2 3\n");  // after a gap: not read
  }

  fs::path dir_;
};

TEST_F(Uos3dtkTest, ReadsPosesAndConvertsFrames) {
  writeValidFolder();
  UosReadStats stats;
  const auto scans = readUos3dtk(dir_.string(), &stats);
  ASSERT_EQ(scans.size(), 3u);

  // Identity pose: uos (x right, y up, z forward, cm) → (z, −x, y) / 100.
  expectPointCm(scans[0].sensor_origin_m, 0, 0, 0);
  ASSERT_EQ(scans[0].points_m.size(), 2u);
  expectPointCm(scans[0].points_m[0], 0, -1, 0);
  expectPointCm(scans[0].points_m[1], 0, 0, 2);

  // .frames: R·(0,0,100) = (100,0,0), plus (100,0,200) → (200,0,200) cm.
  expectPointCm(scans[1].sensor_origin_m, 2, -1, 0);
  ASSERT_EQ(scans[1].points_m.size(), 1u);
  expectPointCm(scans[1].points_m[0], 2, -2, 0);

  // .pose with Rx(90°)·Ry(90°): Ry turns (0,0,100) into (100,0,0), Rx keeps it;
  // plus (100,0,0) → (200,0,0) cm. The other order would give (100,−100,0).
  expectPointCm(scans[2].sensor_origin_m, 0, -1, 0);
  ASSERT_EQ(scans[2].points_m.size(), 1u);
  expectPointCm(scans[2].points_m[0], 0, -2, 0);

  EXPECT_EQ(stats.points_read, 7u);
  EXPECT_EQ(stats.dropped_near, 1u);
  EXPECT_EQ(stats.dropped_far, 1u);
  EXPECT_EQ(stats.dropped_non_finite, 1u);
  EXPECT_EQ(stats.poses_from_frames, 1u);  // only scan001 has a .frames file
}

TEST_F(Uos3dtkTest, RangeLimitsAreInclusiveAsDocumented) {
  write("scan000.3d", "48 0 0\n47.99 0 0\n0 2999.9 0\n0 3000 0\n");
  write("scan000.pose", "0 0 0\n0 0 0\n");
  UosReadStats stats;
  const auto scans = readUos3dtk(dir_.string(), &stats);
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_EQ(scans[0].points_m.size(), 2u);
  EXPECT_EQ(stats.dropped_near, 1u);
  EXPECT_EQ(stats.dropped_far, 1u);
}

TEST_F(Uos3dtkTest, EmptyFramesFallsBackToPose) {
  write("scan000.3d", "0 0 100\n");
  write("scan000.frames", "\n");
  write("scan000.pose", "0 0 50\n0 0 0\n");
  UosReadStats stats;
  const auto scans = readUos3dtk(dir_.string(), &stats);
  expectPointCm(scans.at(0).points_m.at(0), 1.5, 0, 0);
  EXPECT_EQ(stats.poses_from_frames, 0u);
}

TEST_F(Uos3dtkTest, MissingFirstScan) { expectError("no scan000.3d"); }

TEST_F(Uos3dtkTest, MissingPose) {
  write("scan000.3d", "100 0 0\n");
  expectError("scan000.3d: neither .frames nor .pose");
}

TEST_F(Uos3dtkTest, MalformedPoint) {
  writeValidFolder();
  write("scan001.3d", "0 0 100\n0 0 1O0\n");
  expectError("scan001.3d:2: malformed number \"1O0\"");
  write("scan001.3d", "0 0 100 7\n");
  expectError("scan001.3d:1: expected 3 numbers");
}

TEST_F(Uos3dtkTest, MalformedFrames) {
  writeValidFolder();
  write("scan001.frames", "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n");
  expectError("scan001.frames:1: expected 16 matrix values and a type code");
  // Row-major: the translation lands in the last row.
  write("scan001.frames", "1 0 0 100 0 1 0 0 0 0 1 200 0 0 0 1 1\n");
  expectError("scan001.frames:1: matrix is not a rigid transform");
}

TEST_F(Uos3dtkTest, MalformedPose) {
  writeValidFolder();
  write("scan002.pose", "100 0 0\n");
  expectError("scan002.pose: expected a translation line and a rotation line");
  write("scan002.pose", "100 0 0\n90 x 0\n");
  expectError("scan002.pose:2: malformed number \"x\"");
}

/// Median distance from every 97th point of `a` to its nearest point of `b`.
double medianNearestDistance(const PointScan& a, const PointScan& b) {
  std::vector<double> d;
  for (size_t i = 0; i < a.points_m.size(); i += 97) {
    float best = INFINITY;
    for (const Eigen::Vector3f& q : b.points_m) best = std::min(best, (a.points_m[i] - q).squaredNorm());
    d.push_back(std::sqrt(best));
  }
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

TEST(Uos3dtkRealData, ExampleScansOverlap) {
  const std::string dir = std::string(RMAP_SHARED_DATA_DIR) + "/3d-scans/3dtk-example";
  if (!fs::exists(dir)) GTEST_SKIP() << dir << " absent (shared data not available)";
  UosReadStats stats;
  const auto scans = readUos3dtk(dir, &stats);
  ASSERT_EQ(scans.size(), 3u);
  EXPECT_EQ(stats.points_read, 3u * 81360u);
  EXPECT_EQ(stats.poses_from_frames, 3u);
  size_t kept = 0;
  for (const PointScan& s : scans) {
    EXPECT_GT(s.points_m.size(), 75000u);
    EXPECT_LE(s.points_m.size(), 81360u);
    kept += s.points_m.size();
  }
  EXPECT_EQ(kept + stats.dropped_near + stats.dropped_far + stats.dropped_non_finite, 3u * 81360u);
  // The scanner moves forward (x) about 1.6 m between scans.
  EXPECT_NEAR(scans[1].sensor_origin_m.x(), 1.568, 0.01);
  EXPECT_NEAR(scans[2].sensor_origin_m.x(), 3.378, 0.01);
  // Registered consecutive scans see the same surfaces (≈3 cm measured).
  EXPECT_LT(medianNearestDistance(scans[1], scans[0]), 0.1);
  EXPECT_LT(medianNearestDistance(scans[2], scans[1]), 0.1);
}

}  // namespace
}  // namespace rmap::datasets
