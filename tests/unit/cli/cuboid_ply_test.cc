#include "cli/cuboid_ply.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstring>

#include "datasets/ply_cloud.h"

namespace rmap::cli {
namespace {

const std::vector<Cuboid> kCuboids{{{0.0, 0.0, 0.0}, {0.1, 0.2, 0.4}, 0.97f}, {{-1.0, 2.0, 0.5}, {-0.8, 2.1, 0.6}, 0.2f}};

/// The bytes after end_header.
std::string body(const std::string& ply) {
  const std::string marker = "end_header\n";
  return ply.substr(ply.find(marker) + marker.size());
}

TEST(CuboidPly, CentresReadBackWithSizesAndProbabilities) {
  const std::string ply = cuboidCentresPly(kCuboids);
  const datasets::PlyCloud cloud = datasets::parsePlyCloud(ply, "centres.ply");
  ASSERT_EQ(cloud.points_m.size(), 2u);
  EXPECT_TRUE(cloud.points_m[0].isApprox(Eigen::Vector3f(0.05f, 0.1f, 0.2f)));
  EXPECT_TRUE(cloud.points_m[1].isApprox(Eigen::Vector3f(-0.9f, 2.05f, 0.55f)));
  EXPECT_NEAR(cloud.scalars.at("size_z")[0], 0.4f, 1e-6);
  EXPECT_NEAR(cloud.scalars.at("size_x")[1], 0.2f, 1e-6);
  EXPECT_FLOAT_EQ(cloud.scalars.at("probability")[0], 0.97f);
  EXPECT_FLOAT_EQ(cloud.scalars.at("probability")[1], 0.2f);
  EXPECT_EQ(cuboidCentresPly({}).find("element vertex 0\n") != std::string::npos, true);
}

TEST(CuboidPly, MeshHasEightCornersAndSixOutwardQuadsPerCuboid) {
  const std::string ply = cuboidMeshPly(kCuboids);
  EXPECT_NE(ply.find("element vertex 16\n"), std::string::npos);
  EXPECT_NE(ply.find("element face 12\nproperty list uchar int vertex_indices\n"), std::string::npos);
  const std::string data = body(ply);
  constexpr size_t kVertexBytes = 4 * sizeof(float), kFaceBytes = 1 + 4 * sizeof(int32_t);
  ASSERT_EQ(data.size(), 16 * kVertexBytes + 12 * kFaceBytes);
  // The vertices read back as points: the cuboids' corners.
  const datasets::PlyCloud cloud = datasets::parsePlyCloud(ply.substr(0, ply.find("element face")) + "end_header\n" +
                                                               data.substr(0, 16 * kVertexBytes),
                                                           "mesh.ply");
  ASSERT_EQ(cloud.points_m.size(), 16u);
  const auto vertex = [&](int32_t i) { return cloud.points_m[static_cast<size_t>(i)].cast<double>(); };
  for (size_t f = 0; f < 12; ++f) {
    const char* face = data.data() + 16 * kVertexBytes + f * kFaceBytes;
    ASSERT_EQ(face[0], 4);
    int32_t index[4];
    std::memcpy(index, face + 1, sizeof index);
    const size_t cuboid = f / 6;
    Eigen::Vector3d centre = Eigen::Vector3d::Zero(), face_centre = Eigen::Vector3d::Zero();
    for (int k = 0; k < 8; ++k) centre += vertex(static_cast<int32_t>(8 * cuboid + k)) / 8;
    for (int k = 0; k < 4; ++k) {
      ASSERT_GE(index[k], static_cast<int32_t>(8 * cuboid));
      ASSERT_LT(index[k], static_cast<int32_t>(8 * cuboid + 8));
      face_centre += vertex(index[k]) / 4;
    }
    // Counter-clockwise seen from outside: the normal points away from the box's centre.
    const Eigen::Vector3d normal = (vertex(index[1]) - vertex(index[0])).cross(vertex(index[2]) - vertex(index[1]));
    EXPECT_GT(normal.dot(face_centre - centre), 0.0) << "face " << f;
  }
}

}  // namespace
}  // namespace rmap::cli
