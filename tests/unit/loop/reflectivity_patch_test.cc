#include "loop/reflectivity_patch.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace rmap::loop {
namespace {

/// A map with one wall segment along y at x = 2 m (y ∈ [−1, 1]), reflectivity
/// 0.8 on y > 0 and 0.2 on y < 0, seen from the origin.
slam2d::GridMap2d wallMap() {
  slam2d::GridMap2d map(0.05, 1);
  std::vector<slam2d::Ray> rays;
  for (int i = 0; i <= 40; ++i) rays.push_back({Eigen::Vector2d(2.02, -1.0 + 0.05 * i), true});
  slam2d::OccupancyUpdate update;
  for (int k = 0; k < 5; ++k) map.insert(Eigen::Vector2d::Zero(), rays, update, 10.0);
  for (const slam2d::Ray& ray : rays) map.addReflectivity(ray.end_m, ray.end_m.y() > 0 ? 0.8f : 0.2f);
  return map;
}

TEST(ReflectivityPatch, ShowsTheWallAheadWithItsReflectivity) {
  const slam2d::GridMap2d map = wallMap();
  PatchOptions o;
  o.size_px = 100;
  o.pixel_m = 0.05;
  const cv::Mat patch = reflectivityPatch(map, {0.0, 0.0, 0.0}, o);
  ASSERT_EQ(patch.rows, 100);
  ASSERT_EQ(patch.type(), CV_8UC1);
  // 2 m ahead = 40 px above the centre row 50 → row 9; left (y > 0) is left.
  const int row = 9;
  EXPECT_EQ(patch.at<uint8_t>(row, 40), std::lround(64 + 191 * 0.8));
  EXPECT_EQ(patch.at<uint8_t>(row, 60), std::lround(64 + 191 * 0.2));
  EXPECT_EQ(patch.at<uint8_t>(50, 50), 0);  // free space at the robot
  EXPECT_EQ(patch.at<uint8_t>(90, 50), 0);  // unknown behind
}

TEST(ReflectivityPatch, TurnsWithTheRobotHeading) {
  const slam2d::GridMap2d map = wallMap();
  PatchOptions o;
  o.size_px = 100;
  const cv::Mat ahead = reflectivityPatch(map, {0.0, 0.0, 0.0}, o);
  // Facing +y, the wall (at +x) is on the right.
  const cv::Mat turned = reflectivityPatch(map, {0.0, 0.0, std::numbers::pi / 2}, o);
  cv::Mat rotated;
  cv::rotate(ahead, rotated, cv::ROTATE_90_CLOCKWISE);
  EXPECT_LT(cv::norm(rotated, turned, cv::NORM_L1), 0.02 * cv::norm(ahead, cv::NORM_L1));
  EXPECT_GT(cv::countNonZero(turned.colRange(85, 95)), 20);
}

TEST(ReflectivityPatch, BadInputThrows) {
  const slam2d::GridMap2d map = wallMap();
  PatchOptions o;
  o.size_px = 8;
  EXPECT_THROW(reflectivityPatch(map, {}, o), std::invalid_argument);
  o = {};
  o.pixel_m = 0.0;
  EXPECT_THROW(reflectivityPatch(map, {}, o), std::invalid_argument);
  o = {};
  EXPECT_THROW(reflectivityPatch(map, {NAN, 0.0, 0.0}, o), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::loop
