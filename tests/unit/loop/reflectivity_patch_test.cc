#include "loop/reflectivity_patch.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include <opencv2/calib3d.hpp>

#include "loop/binary_features.h"
#include "loop/geometric_verification.h"

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

/// Pixel (x = column, y = row) of the patch around `center` that shows map point `point_m`.
Eigen::Vector2d pixelOf(const slam2d::Pose2& center, const Eigen::Vector2d& point_m, const PatchOptions& o) {
  const Eigen::Vector2d robot = center.inverse() * point_m;
  const double centre_px = 0.5 * o.size_px - 0.5;
  return {centre_px - robot.y() / o.pixel_m, centre_px - robot.x() / o.pixel_m};
}

TEST(ReflectivityPatch, ThePixelsMotionGivesTheRobotsMotion) {
  PatchOptions o;
  const slam2d::Pose2 reference{0.3, -0.2, 0.4}, query{0.9, 0.3, 0.75};
  std::vector<cv::Point2d> from, to;
  for (const Eigen::Vector2d& point : {Eigen::Vector2d(1.0, 1.0), Eigen::Vector2d(-2.0, 0.5),
                                       Eigen::Vector2d(0.5, -3.0), Eigen::Vector2d(2.5, 2.0)}) {
    const Eigen::Vector2d q = pixelOf(query, point, o), r = pixelOf(reference, point, o);
    from.emplace_back(q.x(), q.y());
    to.emplace_back(r.x(), r.y());
  }
  // The pixels' motion fitted by OpenCV ([s·cos, −s·sin, tx; s·sin, s·cos, ty]; exact points: s = 1).
  const cv::Mat fit = cv::estimateAffinePartial2D(from, to);
  ASSERT_FALSE(fit.empty());
  Eigen::Isometry2d pixels = Eigen::Isometry2d::Identity();
  pixels.linear() << fit.at<double>(0, 0), fit.at<double>(0, 1), fit.at<double>(1, 0), fit.at<double>(1, 1);
  pixels.translation() << fit.at<double>(0, 2), fit.at<double>(1, 2);
  const slam2d::Pose2 motion = patchMotion(pixels, o);
  const slam2d::Pose2 truth = slam2d::between(reference, query);
  // OpenCV's fit refines to about 1e-7 px.
  EXPECT_NEAR(motion.x_m, truth.x_m, 1e-5);
  EXPECT_NEAR(motion.y_m, truth.y_m, 1e-5);
  EXPECT_NEAR(motion.theta_rad, truth.theta_rad, 1e-6);
}

/// A 14 × 14 m map of wall segments 0.3–1.5 m long, each of its own reflectivity.
slam2d::GridMap2d segmentsMap(uint32_t seed) {
  slam2d::GridMap2d map(0.05, 1);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> coordinate(-7.0, 7.0), heading(-std::numbers::pi, std::numbers::pi),
      length(0.3, 1.5), reflectivity(0.0, 1.0);
  slam2d::OccupancyUpdate update;
  for (int s = 0; s < 160; ++s) {
    const Eigen::Vector2d start(coordinate(rng), coordinate(rng));
    const Eigen::Vector2d along = Eigen::Rotation2Dd(heading(rng)) * Eigen::Vector2d::UnitX();
    const Eigen::Vector2d normal(-along.y(), along.x());
    const double rho = reflectivity(rng), span_m = length(rng);
    for (double t = 0.0; t <= span_m; t += 0.05) {
      // Seen from 0.15 m off the wall: the short ray leaves the other segments alone.
      const Eigen::Vector2d end = start + t * along;
      const std::vector<slam2d::Ray> ray{{end, true}};
      for (int k = 0; k < 5; ++k) map.insert(end + 0.15 * normal, ray, update, 10.0);
      map.addReflectivity(end, static_cast<float>(rho));
    }
  }
  return map;
}

TEST(ReflectivityPatch, TwoPatchesOfOnePlaceMeasureTheMotionBetweenTheirCentres) {
  const slam2d::GridMap2d map = segmentsMap(5);
  const PatchOptions o;
  const slam2d::Pose2 reference{0.3, -0.2, 0.4}, query{0.9, 0.3, 0.75};
  auto extractor = makeExtractor();
  const Features r = extractor->extract(reflectivityPatch(map, reference, o));
  const Features q = extractor->extract(reflectivityPatch(map, query, o));
  std::vector<cv::Point2f> r_px, q_px;
  for (const cv::KeyPoint& k : r.keypoints) r_px.push_back(k.pt);
  for (const cv::KeyPoint& k : q.keypoints) q_px.push_back(k.pt);
  GeometricVerificationOptions rigid;
  rigid.model = GeometricModel::kRigid2d;
  const Verification v = verifyGeometry(q_px, q.descriptors, r_px, r.descriptors, rigid);
  EXPECT_GT(v.inliers, 30);
  ASSERT_TRUE(v.reference_from_query_px);
  const slam2d::Pose2 motion = patchMotion(*v.reference_from_query_px, o);
  const slam2d::Pose2 truth = slam2d::between(reference, query);
  std::printf("[ patch motion ] %d inliers; measured (%.3f, %.3f, %.2f°), truth (%.3f, %.3f, %.2f°)\n", v.inliers,
              motion.x_m, motion.y_m, motion.theta_rad * 180 / std::numbers::pi, truth.x_m, truth.y_m,
              truth.theta_rad * 180 / std::numbers::pi);
  // Within a pixel (0.05 m) and a degree: nearest-cell rendering moves keypoints by up to a pixel.
  EXPECT_LT(std::hypot(motion.x_m - truth.x_m, motion.y_m - truth.y_m), 0.05);
  EXPECT_LT(std::abs(slam2d::normalizeAngle(motion.theta_rad - truth.theta_rad)), std::numbers::pi / 180);
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
  o.pixel_m = -1.0;
  EXPECT_THROW(patchMotion(Eigen::Isometry2d::Identity(), o), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::loop
