#include "slam2d/trajectory_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace rmap::bench {
namespace {

using slam2d::Pose2;

constexpr double kPi = std::numbers::pi;

/// A square loop of side 4 m, one pose every 0.5 m, heading along the path.
std::vector<Pose2> squareLoop() {
  std::vector<Pose2> poses;
  for (int side = 0; side < 4; ++side) {
    const double heading = side * kPi / 2;
    for (int k = 0; k < 8; ++k) {
      const Pose2 corner = side == 0 ? Pose2{0, 0, 0} : side == 1 ? Pose2{4, 0, 0} : side == 2 ? Pose2{4, 4, 0} : Pose2{0, 4, 0};
      poses.push_back({corner.x_m + 0.5 * k * std::cos(heading), corner.y_m + 0.5 * k * std::sin(heading),
                       slam2d::normalizeAngle(heading)});
    }
  }
  return poses;
}

std::vector<Pose2> transformed(const Pose2& t, const std::vector<Pose2>& poses) {
  std::vector<Pose2> out;
  for (const Pose2& p : poses) out.push_back(t * p);
  return out;
}

TEST(ErrorStats, MeanStdRmseMax) {
  const ErrorStats s = errorStats({1.0, 2.0, 3.0, 6.0});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.mean, 3.0);
  EXPECT_DOUBLE_EQ(s.std, std::sqrt((4.0 + 1.0 + 0.0 + 9.0) / 4.0));
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt((1.0 + 4.0 + 9.0 + 36.0) / 4.0));
  EXPECT_DOUBLE_EQ(s.max, 6.0);
  EXPECT_TRUE(std::isnan(errorStats({}).mean));
}

TEST(TrajectoryMetrics, AlignmentRecoversARigidMotion) {
  const std::vector<Pose2> reference = squareLoop();
  const Pose2 t{3.0, -2.0, 2.5};
  const Pose2 a = alignRigid2d(transformed(t, reference), reference);
  const Pose2 expected = t.inverse();
  EXPECT_NEAR(a.x_m, expected.x_m, 1e-9);
  EXPECT_NEAR(a.y_m, expected.y_m, 1e-9);
  EXPECT_NEAR(a.theta_rad, expected.theta_rad, 1e-9);
  EXPECT_NEAR(absoluteTrajectoryError(transformed(t, reference), reference).max, 0.0, 1e-9);
}

TEST(TrajectoryMetrics, AteOfAConstantOffsetAfterAlignmentIsZeroAndOfNoiseIsItsSize) {
  const std::vector<Pose2> reference = squareLoop();
  // Every other pose pushed 0.1 m outward along y, the rest 0.1 m inward:
  // no rigid motion removes it, so each point keeps its 0.1 m error.
  std::vector<Pose2> estimate = reference;
  for (size_t i = 0; i < estimate.size(); ++i) estimate[i].y_m += i % 2 ? 0.1 : -0.1;
  const ErrorStats ate = absoluteTrajectoryError(estimate, reference);
  EXPECT_NEAR(ate.rmse, 0.1, 1e-9);
  EXPECT_NEAR(ate.mean, 0.1, 1e-9);
  EXPECT_EQ(ate.count, reference.size());
}

TEST(TrajectoryMetrics, RelationErrorsMatchOnStamps) {
  // Straight line along x, poses 1 m apart, stamps 10 s apart.
  std::vector<StampedPose2> trajectory;
  for (int i = 0; i < 5; ++i) trajectory.push_back({int64_t(i) * 10'000'000'000, {double(i), 0.0, 0.0}});
  std::vector<datasets::SlamRelation> relations = {
      {0, 10'000'000'000, {1.0, 0.0, 0.0}, 1},           // exact
      {10'000'000'000, 30'000'000'000, {2.0, 0.3, 0.0}, 2},  // 0.3 m off across
      {20'000'000'000, 40'000'000'000, {2.0, 0.0, 0.1}, 3},  // heading 0.1 rad off, position exact
      {0, 5'000'000'000, {0.5, 0.0, 0.0}, 4},            // t2 not a pose: skipped
  };
  const RelationErrors r = relationErrors(trajectory, relations);
  EXPECT_EQ(r.relations_used, 3u);
  // e = δ_ref⁻¹·δ_est: the third has the same end position, so no translational error
  EXPECT_NEAR(r.translation_m.mean, 0.3 / 3, 1e-12);
  EXPECT_NEAR(r.translation_m.max, 0.3, 1e-12);
  EXPECT_NEAR(r.rotation_rad.mean, 0.1 / 3, 1e-12);
  EXPECT_NEAR(r.rotation_rad.max, 0.1, 1e-12);
}

TEST(TrajectoryMetrics, RelativePoseErrorSeesDriftPerMetre) {
  // Estimate stretched by 2 %: over every 1 m of travel it is 0.02 m off.
  std::vector<Pose2> reference, estimate;
  for (int i = 0; i <= 40; ++i) {
    reference.push_back({0.25 * i, 0.0, 0.0});
    estimate.push_back({0.25 * i * 1.02, 0.0, 0.0});
  }
  const RelativePoseErrors rpe = relativePoseError(estimate, reference, 1.0);
  EXPECT_EQ(rpe.translation_m.count, 37u);  // i = 0..36 reach i + 4
  EXPECT_NEAR(rpe.translation_m.mean, 0.02, 1e-12);
  EXPECT_NEAR(rpe.translation_m.max, 0.02, 1e-12);
  EXPECT_NEAR(rpe.rotation_rad.max, 0.0, 1e-12);
  // a global rigid motion of the estimate changes nothing
  const RelativePoseErrors moved = relativePoseError(transformed({5, 5, 1}, estimate), reference, 1.0);
  EXPECT_NEAR(moved.translation_m.mean, 0.02, 1e-9);
  // a heading error in one pose shows as rotation error of the pairs holding it
  estimate = reference;
  estimate[10].theta_rad = 0.05;
  const RelativePoseErrors turned = relativePoseError(estimate, reference, 1.0);
  EXPECT_NEAR(turned.rotation_rad.max, 0.05, 1e-12);
  EXPECT_EQ(turned.rotation_rad.count, 37u);
  EXPECT_NEAR(turned.rotation_rad.mean, 2 * 0.05 / 37, 1e-12);  // pairs (6, 10) and (10, 14)
}

TEST(TrajectoryMetrics, BadInput) {
  EXPECT_THROW(absoluteTrajectoryError({{}}, {}), std::invalid_argument);
  EXPECT_THROW(relativePoseError({{}}, {{}}, 0.0), std::invalid_argument);
  EXPECT_EQ(relativePoseError({{}}, {{}}, 1.0).translation_m.count, 0u);
}

}  // namespace
}  // namespace rmap::bench
