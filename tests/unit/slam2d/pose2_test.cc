#include "slam2d/pose2.h"

#include <gtest/gtest.h>

#include <numbers>

namespace rmap::slam2d {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(Pose2, NormalizeAngleWrapsIntoHalfOpenInterval) {
  EXPECT_NEAR(normalizeAngle(3.0 * kPi), kPi, 1e-12);
  EXPECT_NEAR(normalizeAngle(-kPi), kPi, 1e-12);
  EXPECT_NEAR(normalizeAngle(2.5 * kPi), 0.5 * kPi, 1e-12);
  EXPECT_NEAR(normalizeAngle(-0.25 * kPi), -0.25 * kPi, 1e-12);
}

TEST(Pose2, ComposeMovesAlongTheHeading) {
  const Pose2 a{1.0, 2.0, kPi / 2};
  const Pose2 b{3.0, 0.0, kPi / 2};
  const Pose2 c = a * b;
  EXPECT_NEAR(c.x_m, 1.0, 1e-12);
  EXPECT_NEAR(c.y_m, 5.0, 1e-12);
  EXPECT_NEAR(c.theta_rad, kPi, 1e-12);
  const Eigen::Vector2d p = a * Eigen::Vector2d(1.0, 0.0);
  EXPECT_NEAR(p.x(), 1.0, 1e-12);
  EXPECT_NEAR(p.y(), 3.0, 1e-12);
}

TEST(Pose2, BetweenUndoesCompose) {
  const Pose2 a{-4.0, 0.5, 2.9};
  const Pose2 d{0.7, -0.2, 0.6};
  const Pose2 r = between(a, a * d);
  EXPECT_NEAR(r.x_m, d.x_m, 1e-12);
  EXPECT_NEAR(r.y_m, d.y_m, 1e-12);
  EXPECT_NEAR(r.theta_rad, d.theta_rad, 1e-12);
  const Pose2 id = a * a.inverse();
  EXPECT_NEAR(id.x_m, 0.0, 1e-12);
  EXPECT_NEAR(id.y_m, 0.0, 1e-12);
  EXPECT_NEAR(id.theta_rad, 0.0, 1e-12);
}

}  // namespace
}  // namespace rmap::slam2d
