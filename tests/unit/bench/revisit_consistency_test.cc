#include "slam2d/revisit_consistency.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace rmap::bench {
namespace {

using slam2d::LaserScan;
using slam2d::Pose2;

struct Wall {
  Eigen::Vector2d a, b;
};

/// An 8 × 6 m room with two pillars, so no two places look alike.
std::vector<Wall> room() {
  std::vector<Wall> walls{{{-4, -3}, {4, -3}}, {{4, -3}, {4, 3}}, {{4, 3}, {-4, 3}}, {{-4, 3}, {-4, -3}}};
  for (const auto& [cx, cy, half] : {std::tuple{2.5, 1.5, 0.3}, std::tuple{-2.0, -1.0, 0.5}}) {
    const Eigen::Vector2d c(cx, cy);
    const Eigen::Vector2d k[4] = {c + Eigen::Vector2d(-half, -half), c + Eigen::Vector2d(half, -half),
                                  c + Eigen::Vector2d(half, half), c + Eigen::Vector2d(-half, half)};
    for (int i = 0; i < 4; ++i) walls.push_back({k[i], k[(i + 1) % 4]});
  }
  return walls;
}

/// A noise-free 180° scan, 181 beams, from `sensor`.
LaserScan scanFrom(const Pose2& sensor, const std::vector<Wall>& walls) {
  LaserScan scan;
  scan.range_min_m = 0.1f;
  scan.range_max_m = 30.0f;
  for (int i = 0; i <= 180; ++i) {
    const double angle = -std::numbers::pi / 2 + i * std::numbers::pi / 180;
    const Eigen::Vector2d o = sensor.translation();
    const Eigen::Vector2d d(std::cos(sensor.theta_rad + angle), std::sin(sensor.theta_rad + angle));
    double nearest = std::numeric_limits<double>::infinity();
    for (const Wall& w : walls) {
      const Eigen::Vector2d e = w.b - w.a;
      const double den = d.x() * e.y() - d.y() * e.x();
      if (std::abs(den) < 1e-12) continue;
      const Eigen::Vector2d ao = w.a - o;
      const double t = (ao.x() * e.y() - ao.y() * e.x()) / den, u = (ao.x() * d.y() - ao.y() * d.x()) / den;
      if (t > 0 && u >= 0 && u <= 1) nearest = std::min(nearest, t);
    }
    scan.angles_rad.push_back(float(angle));
    scan.ranges_m.push_back(float(nearest));
  }
  return scan;
}

/// Two laps of a 2 m circle about the room's centre, heading along the path, 60 poses a lap.
std::vector<Pose2> twoLaps() {
  std::vector<Pose2> poses;
  for (int k = 0; k < 120; ++k) {
    const double a = 2 * std::numbers::pi * k / 60;
    poses.push_back({2.0 * std::cos(a), 2.0 * std::sin(a), slam2d::normalizeAngle(a + std::numbers::pi / 2)});
  }
  return poses;
}

std::vector<LaserScan> scansAlong(const std::vector<Pose2>& poses) {
  std::vector<LaserScan> scans;
  for (const Pose2& p : poses) scans.push_back(scanFrom(p, room()));
  return scans;
}

/// The trajectory as a front end that turns a little too far every step would draw it.
std::vector<Pose2> withHeadingDrift(const std::vector<Pose2>& truth, double drift_rad_per_step) {
  std::vector<Pose2> out{truth.front()};
  for (size_t k = 1; k < truth.size(); ++k)
    out.push_back(out.back() * slam2d::between(truth[k - 1], truth[k]) * Pose2{0, 0, drift_rad_per_step});
  return out;
}

TEST(RevisitConsistency, TheTrueTrajectoryFitsItsOwnScans) {
  const std::vector<Pose2> truth = twoLaps();
  const RevisitConsistency c = revisitConsistency(scansAlong(truth), {truth});
  // The second lap passes every pose of the first within 2 m: many revisits.
  EXPECT_GT(c.pairs, 60u);
  ASSERT_EQ(c.residual_m.size(), 1u);
  // Noise-free scans: only the beam spacing between the two visits' endpoints is left.
  EXPECT_LT(c.residual_m[0], 0.03);
  EXPECT_EQ(c.lowest[0], c.pairs);
}

TEST(RevisitConsistency, ADriftedTrajectoryFitsWorseOnTheSameRevisits) {
  const std::vector<Pose2> truth = twoLaps();
  const std::vector<Pose2> drifted = withHeadingDrift(truth, 0.003);  // 0.36 rad over the run
  const RevisitConsistency c = revisitConsistency(scansAlong(truth), {drifted, truth});
  ASSERT_EQ(c.residual_m.size(), 2u);
  EXPECT_GT(c.residual_m[0], 2.0 * c.residual_m[1]);
  EXPECT_GT(c.lowest[1], c.pairs * 9 / 10) << "the truth fits nearly every revisit better";
  EXPECT_EQ(c.lowest[0] + c.lowest[1], c.pairs);
  // Each revisit is listed with both residuals, which square-average to the figures.
  ASSERT_EQ(c.revisits.size(), c.pairs);
  double sum_squared[2] = {0.0, 0.0};
  for (const RevisitConsistency::Revisit& r : c.revisits) {
    EXPECT_GE(r.later, r.earlier + RevisitConsistencyOptions{}.min_scan_gap);
    EXPECT_GT(r.points, 0u);
    for (int t = 0; t < 2; ++t) sum_squared[t] += r.residual_m[t] * r.residual_m[t];
  }
  for (int t = 0; t < 2; ++t) EXPECT_NEAR(std::sqrt(sum_squared[t] / double(c.pairs)), c.residual_m[t], 1e-12);
  // Truncation bounds any trajectory's residual.
  const RevisitConsistency lost = revisitConsistency(scansAlong(truth), {withHeadingDrift(truth, 0.05)});
  EXPECT_LE(lost.residual_m[0], RevisitConsistencyOptions{}.truncation_m + 1e-12);
}

TEST(RevisitConsistency, IdenticalTrajectoriesTieAndTiesGoToTheFirst) {
  const std::vector<Pose2> truth = twoLaps();
  const RevisitConsistency c = revisitConsistency(scansAlong(truth), {truth, truth});
  EXPECT_DOUBLE_EQ(c.residual_m[0], c.residual_m[1]);
  EXPECT_EQ(c.lowest[0], c.pairs);
  EXPECT_EQ(c.lowest[1], 0u);
}

TEST(RevisitConsistency, OnlyScansFarApartInSequenceAndNearInPlaceArePaired) {
  const std::vector<Pose2> truth = twoLaps();
  const std::vector<LaserScan> scans = scansAlong(truth);
  // Half a lap never comes back: no revisit, and no residual.
  const std::vector<Pose2> half(truth.begin(), truth.begin() + 30);
  const RevisitConsistency none = revisitConsistency({scans.begin(), scans.begin() + 30}, {half});
  EXPECT_EQ(none.pairs, 0u);
  EXPECT_TRUE(std::isnan(none.residual_m[0]));
  RevisitConsistencyOptions o;
  o.min_scan_gap = 120;  // longer than the run
  EXPECT_EQ(revisitConsistency(scans, {truth}, o).pairs, 0u);
  o = {};
  o.max_heading_rad = 0.01;
  o.max_distance_m = 0.01;  // the laps' poses coincide, so only the same pose a lap later is paired
  EXPECT_EQ(revisitConsistency(scans, {truth}, o).pairs, 60u);
  o.max_pairs = 10;
  EXPECT_EQ(revisitConsistency(scans, {truth}, o).pairs, 10u);
}

TEST(RevisitConsistency, PosesMissingOrNonFiniteAreLeftOut) {
  std::vector<Pose2> truth = twoLaps();
  const std::vector<LaserScan> scans = scansAlong(truth);
  RevisitConsistencyOptions o;
  o.max_heading_rad = 0.01;
  o.max_distance_m = 0.01;
  truth[70].x_m = std::nan("");
  const RevisitConsistency c = revisitConsistency(scans, {truth}, o);
  EXPECT_EQ(c.pairs, 59u);
  EXPECT_LT(c.residual_m[0], 0.01);
}

TEST(RevisitConsistency, RefusesMismatchedInput) {
  const std::vector<Pose2> truth = twoLaps();
  const std::vector<LaserScan> scans = scansAlong(truth);
  EXPECT_THROW(revisitConsistency(scans, {}), std::invalid_argument);
  EXPECT_THROW(revisitConsistency(scans, {truth, {truth.begin(), truth.end() - 1}}), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::bench
