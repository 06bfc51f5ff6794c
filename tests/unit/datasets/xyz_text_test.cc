#include "datasets/xyz_text.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <stdexcept>
#include <string>

#include "dataset_test_support.h"

namespace rmap::datasets {
namespace {

void expectXyzError(const std::string& text, const std::string& part) {
  expectParseError([](const std::string& c) { parseXyzText(c, "test.dat"); }, text, part);
}

TEST(XyzText, PlainPointsAreOneScanAtTheOrigin) {
  const auto scans = parseXyzText("# header\n1 2 3\n\n  -0.5\t4.25 1e-3\r\n+7 -0 2.5 # trailing comment\n", "t");
  ASSERT_EQ(scans.size(), 1u);
  EXPECT_EQ(scans[0].sensor_origin_m, Eigen::Vector3f::Zero());
  ASSERT_EQ(scans[0].points_m.size(), 3u);
  expectPoint(scans[0].points_m[0], 1, 2, 3);
  expectPoint(scans[0].points_m[1], -0.5, 4.25, 0.001);
  expectPoint(scans[0].points_m[2], 7, 0, 2.5);
}

TEST(XyzText, EmptyTextHasNoScans) {
  EXPECT_TRUE(parseXyzText("", "t").empty());
  EXPECT_TRUE(parseXyzText("# only a comment\n\n", "t").empty());
}

TEST(XyzText, NodeLinesStartPosedScans) {
  const double half_pi = std::numbers::pi / 2;
  const std::string text = "NODE 1 2 3 0 0 " + std::to_string(half_pi) +
                           "\n"
                           "1 0 0\n"
                           "0 1 0.5\n"
                           "NODE 0 0 1 " + std::to_string(half_pi) + " 0 0\n"
                           "0 1 0\n"
                           "NODE 5 5 5 0 0 0\n";
  const auto scans = parseXyzText(text, "t");
  ASSERT_EQ(scans.size(), 3u);
  expectPoint(scans[0].sensor_origin_m, 1, 2, 3);
  ASSERT_EQ(scans[0].points_m.size(), 2u);
  expectPoint(scans[0].points_m[0], 1, 3, 3);    // yaw 90°: x → y
  expectPoint(scans[0].points_m[1], 0, 2, 3.5);  // y → −x
  expectPoint(scans[1].sensor_origin_m, 0, 0, 1);
  ASSERT_EQ(scans[1].points_m.size(), 1u);
  expectPoint(scans[1].points_m[0], 0, 0, 2);  // roll 90°: y → z
  expectPoint(scans[2].sensor_origin_m, 5, 5, 5);
  EXPECT_TRUE(scans[2].points_m.empty());
}

TEST(XyzText, EulerOrderIsYawPitchRoll) {
  // Rz(yaw)·Ry(pitch)·Rx(roll) as octomath::Pose6D: roll first, in the sensor frame.
  const double q = std::numbers::pi / 2;
  const auto scans =
      parseXyzText("NODE 0 0 0 " + std::to_string(q) + " " + std::to_string(q) + " 0\n0 1 0\n", "t");
  ASSERT_EQ(scans.size(), 1u);
  // roll: (0,1,0) → (0,0,1); then pitch: (0,0,1) → (1,0,0).
  expectPoint(scans[0].points_m[0], 1, 0, 0);
}

TEST(XyzText, PointsBeforeTheFirstNodeKeepTheOrigin) {
  const auto scans = parseXyzText("1 1 1\nNODE 1 0 0 0 0 0\n1 1 1\n", "t");
  ASSERT_EQ(scans.size(), 2u);
  expectPoint(scans[0].points_m[0], 1, 1, 1);
  expectPoint(scans[1].points_m[0], 2, 1, 1);
}

TEST(XyzText, ErrorsNameTheLine) {
  expectXyzError("1 2 3\n1 2 x\n", "test.dat:2: malformed number \"x\"");
  expectXyzError("1 2 3\n\n1 2\n", "test.dat:3: expected 3 numbers");
  expectXyzError("1 2 3 4\n", "test.dat:1: expected 3 numbers");
  expectXyzError("1 2 3.5.6\n", "test.dat:1: malformed number");
  expectXyzError("1 nan 3\n", "test.dat:1: non-finite");
  expectXyzError("1 2 1e999\n", "test.dat:1: number out of range");
  expectXyzError("NODE 1 2 3 0 0\n", "test.dat:1: NODE needs x y z roll pitch yaw, got 5");
  expectXyzError("NODE 1 2 3 0 0 zz\n", "test.dat:1: malformed number \"zz\"");
}

TEST(XyzText, MissingFileNamesPath) {
  try {
    readXyzText("/nonexistent/scan.dat");
    ADD_FAILURE();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scan.dat"), std::string::npos) << e.what();
  }
}

TEST(XyzTextRealData, OctomapScanDat) {
  const std::string p = std::string(RMAP_SHARED_DATA_DIR) + "/octomap/scan.dat.bz2";
  if (!std::filesystem::exists(p)) GTEST_SKIP() << p << " absent (shared data not available)";
  const auto scans = readXyzText(p);
  ASSERT_EQ(scans.size(), 1u);  // the file has no NODE lines
  EXPECT_EQ(scans[0].sensor_origin_m, Eigen::Vector3f::Zero());
  ASSERT_EQ(scans[0].points_m.size(), 88206u);
  expectPoint(scans[0].points_m.front(), -0.0434742, -4.82982, 0.499645);
  expectPoint(scans[0].points_m.back(), 0.130896, 3.58, 0.432014);
}

}  // namespace
}  // namespace rmap::datasets
