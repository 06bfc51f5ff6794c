#include "datasets/ply_cloud.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "dataset_test_support.h"

namespace rmap::datasets {
namespace {

void expectPlyError(const std::string& content, const std::string& part) {
  expectParseError([](const std::string& c) { parsePlyCloud(c, "t.ply"); }, content, part);
}

TEST(PlyCloud, BinaryLittleEndianWithIntensity) {
  std::string ply =
      "ply\nformat binary_little_endian 1.0\ncomment made by hand\nobj_info test\n"
      "element vertex 2\nproperty float x\nproperty float y\nproperty float z\nproperty float scalar_intensity\n"
      "end_header\n";
  for (float v : {1.0f, 2.0f, 3.0f, 0.25f, -4.5f, 0.0f, 1e-3f, 17.0f}) appendBinary(ply, v);
  const PlyCloud cloud = parsePlyCloud(ply, "t.ply");
  ASSERT_EQ(cloud.points_m.size(), 2u);
  EXPECT_EQ(cloud.points_m[0], Eigen::Vector3f(1, 2, 3));
  EXPECT_EQ(cloud.points_m[1], Eigen::Vector3f(-4.5f, 0, 1e-3f));
  ASSERT_EQ(cloud.scalars.size(), 1u);
  EXPECT_EQ(cloud.scalars.at("scalar_intensity"), (std::vector<float>{0.25f, 17.0f}));
}

TEST(PlyCloud, BigEndianMixedTypesAndElementsAround) {
  std::string ply =
      "ply\r\nformat binary_big_endian 1.0\r\nelement camera 1\r\nproperty uchar id\r\nproperty double f\r\n"
      "element vertex 1\r\nproperty double z\r\nproperty ushort ring\r\nproperty double x\r\nproperty int8 tag\r\n"
      "property double y\r\nelement face 3\r\nproperty list uchar int vertex_indices\r\nend_header\r\n";
  appendBinary(ply, uint8_t{7}, true), appendBinary(ply, 1.5, true);            // camera
  appendBinary(ply, 3.0, true), appendBinary(ply, uint16_t{31}, true), appendBinary(ply, -1.0, true), appendBinary(ply, int8_t{-2}, true), appendBinary(ply, 2.0, true);
  ply += "face data is ignored";
  const PlyCloud cloud = parsePlyCloud(ply, "t.ply");
  ASSERT_EQ(cloud.points_m.size(), 1u);
  EXPECT_EQ(cloud.points_m[0], Eigen::Vector3f(-1, 2, 3));
  EXPECT_EQ(cloud.scalars.at("ring")[0], 31.0f);
  EXPECT_EQ(cloud.scalars.at("tag")[0], -2.0f);
}

TEST(PlyCloud, Ascii) {
  const PlyCloud cloud = parsePlyCloud(
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
      "property uchar intensity\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 1 200\n0.5 -1 2e1 3\n3 0 1 1\n",
      "t.ply");
  ASSERT_EQ(cloud.points_m.size(), 2u);
  EXPECT_EQ(cloud.points_m[1], Eigen::Vector3f(0.5f, -1, 20));
  EXPECT_EQ(cloud.scalars.at("intensity"), (std::vector<float>{200, 3}));
}

TEST(PlyCloud, MalformedFilesAreRejectedWithTheReason) {
  const std::string head = "ply\nformat binary_little_endian 1.0\nelement vertex 2\n";
  expectPlyError("PLY\n", "not a PLY file");
  expectPlyError(head + "property float x\nproperty float y\nend_header\n", "no property 'z'");
  expectPlyError(head + "property float x\nproperty float y\nproperty float z\n", "no end_header");
  expectPlyError(head + "property half x\nend_header\n", "t.ply:4: unsupported property");
  expectPlyError("ply\nformat binary_middle_endian 1.0\nend_header\n", "t.ply:2: unknown format");
  expectPlyError(head + "property float x\nproperty float y\nproperty float z\nend_header\n" + std::string(20, '\0'),
              "binary data ends in element 'vertex'");
  expectPlyError("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
              "end_header\n1 2\n",
              "t.ply:8: vertex needs 3 values, got 2");
  expectPlyError("ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar float x\nend_header\n", "is a list");
}

// Found by tests/fuzz/ply_cloud_fuzz.cc: a count of 2^64 or more was cast to size_t (undefined),
// and a large count took its memory before the data was checked.
TEST(PlyCloud, CountsBeyondTheDataAreRefusedBeforeMemoryIsTaken) {
  const std::string xyz = "property float x\nproperty float y\nproperty float z\nend_header\n";
  expectPlyError("ply\nformat ascii 1.0\nelement vertex 3.55556e+21\n" + xyz, "t.ply:3: element count");
  expectPlyError("ply\nformat ascii 1.0\nelement vertex 18446744073709551616\n" + xyz, "t.ply:3: element count");
  expectPlyError("ply\nformat ascii 1.0\nelement vertex 1e15\n" + xyz + "1 2 3\n",
              "declares 1000000000000000 vertices, more than the 6 bytes of ascii data");
  expectPlyError("ply\nformat ascii 1.0\nelement vertex 4\n" + xyz + "1 2 3\n", "more than the 6 bytes");
  expectPlyError("ply\nformat binary_little_endian 1.0\nelement vertex 1e15\n" + xyz + std::string(12, '\0'),
              "binary data ends in element 'vertex'");
  // The bound is not tighter than the data: one-character values, no final '\n'; a vertex line
  // too short for its values is refused by name.
  EXPECT_EQ(parsePlyCloud("ply\nformat ascii 1.0\nelement vertex 2\n" + xyz + "1 2 3\n4 5 6", "t.ply").points_m.size(),
            2u);
  expectPlyError("ply\nformat ascii 1.0\nelement vertex 2\n" + xyz + "1 2 3\n4", "t.ply:9: vertex needs 3 values, got 1");
}

// Seen while fixing that: binary data was looked for after the first "\nend_header" of the
// file, not after the line that ended the header.
TEST(PlyCloud, BinaryDataStartsAfterTheHeaderLine) {
  std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
      "property float z\n  end_header\n";
  for (float v : {1.0f, 2.0f, 3.0f}) appendBinary(ply, v);
  const PlyCloud cloud = parsePlyCloud(ply, "t.ply");
  ASSERT_EQ(cloud.points_m.size(), 1u);
  EXPECT_EQ(cloud.points_m[0], Eigen::Vector3f(1, 2, 3));
}

TEST(PlyCloud, ReadsTheSharedLidarScan) {
  const std::string path = std::string(RMAP_SHARED_DATA_DIR) + "/lidar-intensity/small-gicp-pair/source.ply";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared data not found: " << path;
  const PlyCloud cloud = readPlyCloud(path);
  ASSERT_EQ(cloud.points_m.size(), 69792u);  // the header's vertex count
  const std::vector<float>& intensity = cloud.scalars.at("scalar_intensity");
  ASSERT_EQ(intensity.size(), cloud.points_m.size());
  size_t returns = 0;
  for (size_t i = 0; i < intensity.size(); ++i) {
    if (cloud.points_m[i].squaredNorm() == 0.0f) continue;
    ++returns;
    ASSERT_TRUE(std::isfinite(intensity[i])) << i;
    ASSERT_LT(cloud.points_m[i].norm(), 200.0f) << i;
  }
  EXPECT_GT(returns, 60000u);
}

}  // namespace
}  // namespace rmap::datasets
