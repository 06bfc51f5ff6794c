#include "datasets/pose_file.h"

#include <gtest/gtest.h>

#include "dataset_test_support.h"

namespace rmap::datasets {
namespace {

TEST(PoseFile, KittiRowMajor) {
  const std::vector<StampedPose3> poses = parsePoseFile(
      "1 0 0 0 0 1 0 0 0 0 1 0\n"
      "# a comment\n\n"
      "0 -1 0 1.5 1 0 0 -2 0 0 1 3\n",
      "poses.txt");
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_FALSE(poses[0].stamp_ns);
  EXPECT_TRUE(poses[0].pose.isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_EQ(poses[1].line, 4u);
  EXPECT_TRUE(poses[1].pose.translation().isApprox(Eigen::Vector3d(1.5, -2, 3)));
  // 90° about z: x goes to y.
  EXPECT_TRUE((poses[1].pose.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY()));
}

TEST(PoseFile, TumWithStamps) {
  const std::vector<StampedPose3> poses = parsePoseFile("1305031102.175304 1 2 3 0 0 0.7071068 0.7071068\n", "t.txt");
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_EQ(*poses[0].stamp_ns, 1305031102175304000);
  EXPECT_TRUE(poses[0].pose.translation().isApprox(Eigen::Vector3d(1, 2, 3)));
  EXPECT_TRUE((poses[0].pose.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-6));
}

TEST(PoseFile, BadInputIsNamed) {
  const auto parse = [](const std::string& c) { parsePoseFile(c, "p.txt"); };
  expectParseError(parse, "1 2 3\n", "p.txt:1: 3 fields");
  expectParseError(parse, "1 0 0 0 0 1 0 0 0 0 1 0\n0 0 0 0 0 0 0 1\n", "p.txt:2: 8 fields where the file's first");
  expectParseError(parse, "2 0 0 0 0 1 0 0 0 0 1 0\n", "p.txt:1: the 3x3 rotation is not orthonormal");
  expectParseError(parse, "0 1 2 3 0 0 0 0\n", "p.txt:1: the quaternion is zero");
  expectParseError(parse, "1 0 0 nan 0 1 0 0 0 0 1 0\n", "p.txt:1: field 4 is not finite");
  expectParseError(parse, "1 0 0 x 0 1 0 0 0 0 1 0\n", "p.txt:1");
}

}  // namespace
}  // namespace rmap::datasets
