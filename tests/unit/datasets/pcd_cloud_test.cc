#include "datasets/pcd_cloud.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "dataset_test_support.h"

namespace rmap::datasets {
namespace {

const auto kParsePcd = [](const std::string& c) { parsePcdCloud(c, "t.pcd"); };

TEST(PcdCloud, AsciiWithIntensity) {
  const PcdCloud cloud = parsePcdCloud(
      "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\n"
      "TYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
      "1 2 3 0.5\n-1.5 0 2e-1 40\n",
      "t.pcd");
  ASSERT_EQ(cloud.points_m.size(), 2u);
  EXPECT_EQ(cloud.points_m[1], Eigen::Vector3f(-1.5f, 0.0f, 0.2f));
  EXPECT_EQ(cloud.intensities, (std::vector<float>{0.5f, 40.0f}));
}

TEST(PcdCloud, BinaryMixedTypesAndArrayField) {
  std::string pcd =
      "VERSION .7\nFIELDS intensity normal x y z ring\nSIZE 2 4 8 8 8 1\nTYPE U F F F F U\nCOUNT 1 3 1 1 1 1\n"
      "WIDTH 1\nHEIGHT 2\nPOINTS 2\nDATA binary\n";
  for (int k = 0; k < 2; ++k) {
    appendBinary(pcd, uint16_t(100 + k));
    for (int n = 0; n < 3; ++n) appendBinary(pcd, 9.0f);
    appendBinary(pcd, 1.0 + k), appendBinary(pcd, 2.0), appendBinary(pcd, -3.0);
    appendBinary(pcd, uint8_t(7));
  }
  const PcdCloud cloud = parsePcdCloud(pcd, "t.pcd");
  ASSERT_EQ(cloud.points_m.size(), 2u);
  EXPECT_EQ(cloud.points_m[0], Eigen::Vector3f(1, 2, -3));
  EXPECT_EQ(cloud.points_m[1], Eigen::Vector3f(2, 2, -3));
  EXPECT_EQ(cloud.intensities, (std::vector<float>{100.0f, 101.0f}));
}

TEST(PcdCloud, NoIntensityAndNanPointsKept) {
  std::string pcd = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 1\nDATA binary\n";
  for (float v : {1.0f, 1.0f, 1.0f, NAN, NAN, NAN}) appendBinary(pcd, v);
  const PcdCloud cloud = parsePcdCloud(pcd, "t.pcd");
  ASSERT_EQ(cloud.points_m.size(), 2u);
  EXPECT_TRUE(cloud.intensities.empty());
  EXPECT_TRUE(std::isnan(cloud.points_m[1].x()));
}

TEST(PcdCloud, BadInputIsNamed) {
  const std::string head = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n";
  expectParseError(kParsePcd, head + "DATA ascii\n1 2 3\n4 5\n", "t.pcd:10: 2 values, expected 3");
  expectParseError(kParsePcd, head + "DATA ascii\n1 2 3\n", "truncated: 1 of 2 points");
  expectParseError(kParsePcd, head + "DATA ascii\n1 2 3\n4 x 6\n", "t.pcd:10");
  const std::string binary = head + "DATA binary\n";
  expectParseError(kParsePcd, binary + std::string(20, '\0'), "offset " + std::to_string(binary.size()) + ": truncated");
  expectParseError(kParsePcd, head + "DATA binary_compressed\n", "binary_compressed is not supported");
  expectParseError(kParsePcd, "FIELDS x y\nSIZE 4 4\nTYPE F F\nWIDTH 1\nDATA ascii\n1 2\n", "must include x, y and z");
  expectParseError(kParsePcd, "FIELDS x y z\nSIZE 4 4\n", "t.pcd:2: SIZE lists 2 values for 3 FIELDS");
  expectParseError(kParsePcd, "FIELDS x y z\nSIZE 4 4 3\n", "SIZE must be 1, 2, 4 or 8");
  expectParseError(kParsePcd, "FIELDS x y z\nTYPE F F Q\n", "TYPE must be F, I or U");
  expectParseError(kParsePcd, "FIELDS x y z\nWIDTH 2\nHEIGHT 2\nPOINTS 3\nDATA ascii\n", "POINTS 3 is not WIDTH");
  expectParseError(kParsePcd, "FIELDS x y z\nWIDTH 1\n", "header ends without a DATA line");
  expectParseError(kParsePcd, "FIELDS x y z\nFOO 1\nDATA ascii\n", "t.pcd:2: unexpected header line");
}

}  // namespace
}  // namespace rmap::datasets
