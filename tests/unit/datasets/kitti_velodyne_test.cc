#include "datasets/kitti_velodyne.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "dataset_test_support.h"

namespace rmap::datasets {
namespace {

std::string records(const std::vector<float>& values) {
  std::string out(values.size() * sizeof(float), '\0');
  std::memcpy(out.data(), values.data(), out.size());
  return out;
}

TEST(KittiVelodyne, ReadsPointsAndIntensities) {
  const VelodyneFrame frame = parseVelodyneBin(records({1, 2, 3, 0.5f, -4, 5.5f, 0, 0.25f}), "t.bin");
  ASSERT_EQ(frame.points_m.size(), 2u);
  EXPECT_EQ(frame.points_m[1], Eigen::Vector3f(-4, 5.5f, 0));
  EXPECT_EQ(frame.intensities, (std::vector<float>{0.5f, 0.25f}));
  EXPECT_TRUE(parseVelodyneBin("", "t.bin").points_m.empty());
}

TEST(KittiVelodyne, BadInputIsNamed) {
  const auto parse = [](const std::string& c) { parseVelodyneBin(c, "t.bin"); };
  expectParseError(parse, records({1, 2, 3, 4}) + "abc", "t.bin: 19 bytes is not a whole number");
  expectParseError(parse, records({1, 2, 3, 4, 1, NAN, 3, 4}), "t.bin: offset 20: point 1 has a non-finite value");
}

}  // namespace
}  // namespace rmap::datasets
