#include "slam2d/incidence.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>

#include "angles.h"

namespace rmap::slam2d {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

/// Beams from −fov/2 to +fov/2 at `step_deg`, ranges filled by the caller.
LaserScan fan(double fov_deg, double step_deg) {
  LaserScan scan;
  scan.range_min_m = 0.05f;
  scan.range_max_m = 30.0f;
  const int beams = static_cast<int>(std::lround(fov_deg / step_deg)) + 1;
  for (int i = 0; i < beams; ++i) scan.angles_rad.push_back(float((-0.5 * fov_deg + i * step_deg) * kDeg));
  scan.ranges_m.assign(beams, kInf);
  return scan;
}

/// Range along beam angle phi to the line {p : n·p = d} (unit n), +inf when the beam misses it.
float rangeToLine(double phi, const Eigen::Vector2d& n, double d) {
  const double denom = n.dot(Eigen::Vector2d(std::cos(phi), std::sin(phi)));
  const double r = denom > 1e-9 ? d / denom : std::numeric_limits<double>::infinity();
  return float(r);
}

TEST(CosIncidence, WallFacingTheSensorGivesCosineOfBeamAngle) {
  LaserScan scan = fan(120.0, 0.5);
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) scan.ranges_m[i] = rangeToLine(scan.angles_rad[i], {1, 0}, 2.0);
  const std::vector<float> c = cosIncidence(scan);
  ASSERT_EQ(c.size(), scan.ranges_m.size());
  for (size_t i = 0; i < c.size(); ++i) {
    ASSERT_NEAR(c[i], std::cos(scan.angles_rad[i]), 1e-4) << "beam " << i;
  }
}

TEST(CosIncidence, NoisyObliqueWallStaysWithinAFewDegrees) {
  LaserScan scan = fan(270.0, 0.25);
  const Eigen::Vector2d n = Eigen::Vector2d(std::cos(0.4), std::sin(0.4));
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const float r = rangeToLine(scan.angles_rad[i], n, 3.0);
    if (std::isfinite(r) && r < 25.0f) scan.ranges_m[i] = float(r + noise(rng));
  }
  const std::vector<float> c = cosIncidence(scan);
  int estimated = 0, returns = 0;
  double sum_abs_deg = 0.0;
  for (size_t i = 0; i < c.size(); ++i) {
    if (!std::isfinite(scan.ranges_m[i])) {
      EXPECT_TRUE(std::isnan(c[i]));
      continue;
    }
    const double truth = n.dot(Eigen::Vector2d(std::cos(scan.angles_rad[i]), std::sin(scan.angles_rad[i])));
    if (truth < std::cos(75 * kDeg)) continue;  // beyond the grazing limit of interest
    ++returns;
    if (std::isnan(c[i])) continue;
    ++estimated;
    sum_abs_deg += std::abs(std::acos(std::min(1.0f, c[i])) - std::acos(truth)) / kDeg;
  }
  ASSERT_GT(returns, 300);
  EXPECT_GT(estimated, 0.97 * returns);
  EXPECT_LT(sum_abs_deg / estimated, 1.5);
}

TEST(CosIncidence, RangeJumpKeepsTheSurfacesApart) {
  // A wall at x = 4 and, in front of it between φ = 10° and 30°, a panel on
  // the line x + y = 2.
  LaserScan scan = fan(90.0, 0.5);
  const Eigen::Vector2d panel_n = Eigen::Vector2d(1.0, 1.0).normalized();
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double phi = scan.angles_rad[i];
    const bool on_panel = phi > 10 * kDeg && phi < 30 * kDeg;
    scan.ranges_m[i] = on_panel ? rangeToLine(phi, panel_n, 2.0 * panel_n.x()) : rangeToLine(phi, {1, 0}, 4.0);
    ASSERT_TRUE(std::isfinite(scan.ranges_m[i]));
  }
  const std::vector<float> c = cosIncidence(scan);
  for (size_t i = 0; i < c.size(); ++i) {
    const double phi = scan.angles_rad[i];
    const bool on_panel = phi > 10 * kDeg && phi < 30 * kDeg;
    const Eigen::Vector2d u(std::cos(phi), std::sin(phi));
    const double truth = std::abs((on_panel ? panel_n : Eigen::Vector2d(1, 0)).dot(u));
    ASSERT_FALSE(std::isnan(c[i])) << "beam " << i;
    ASSERT_NEAR(c[i], truth, 1e-3) << "beam " << i << " at " << phi / kDeg << "°";
  }
}

TEST(CosIncidence, CornerUsesTheOneSidedLine) {
  // Room corner: wall x = 2 and wall y = 2 meet at (2, 2), beam 45°.
  LaserScan scan = fan(80.0, 0.5);
  for (float& a : scan.angles_rad) a += float(45 * kDeg);
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    scan.ranges_m[i] = std::min(rangeToLine(scan.angles_rad[i], {1, 0}, 2.0), rangeToLine(scan.angles_rad[i], {0, 1}, 2.0));
  }
  const std::vector<float> c = cosIncidence(scan);
  for (size_t i = 0; i < c.size(); ++i) {
    const double phi = scan.angles_rad[i];
    if (std::abs(phi - 45 * kDeg) < 0.26 * kDeg) continue;  // the corner beam itself is on both walls
    const double truth = phi < 45 * kDeg ? std::cos(phi) : std::sin(phi);
    ASSERT_FALSE(std::isnan(c[i])) << "beam " << i;
    ASSERT_NEAR(c[i], truth, 1e-3) << "beam at " << phi / kDeg << "°";
  }
}

TEST(CosIncidence, NoReturnsAndIsolatedReturnsHaveNone) {
  LaserScan scan = fan(60.0, 1.0);
  scan.range_max_m = 10.0f;
  scan.ranges_m[5] = 3.0f;                                           // isolated
  scan.ranges_m[20] = 12.0f, scan.ranges_m[21] = 12.0f, scan.ranges_m[22] = 12.0f;  // beyond range_max_m
  scan.ranges_m[30] = std::numeric_limits<float>::quiet_NaN();
  for (int i = 40; i < 45; ++i) scan.ranges_m[i] = rangeToLine(scan.angles_rad[i], {1, 0}, 2.0);
  const std::vector<float> c = cosIncidence(scan);
  for (size_t i = 0; i < c.size(); ++i) {
    if (i >= 40 && i < 45) {
      EXPECT_NEAR(c[i], std::cos(scan.angles_rad[i]), 1e-4) << "beam " << i;
    } else {
      EXPECT_TRUE(std::isnan(c[i])) << "beam " << i;
    }
  }
  EXPECT_TRUE(cosIncidence(LaserScan{}).empty());
}

TEST(CosIncidence, RejectsMismatchedSizesAndBadOptions) {
  LaserScan scan = fan(10.0, 1.0);
  scan.ranges_m.pop_back();
  EXPECT_THROW(cosIncidence(scan), std::invalid_argument);
  scan.ranges_m.push_back(1.0f);
  IncidenceOptions o;
  o.max_incidence_deg = 90.0;
  EXPECT_THROW(cosIncidence(scan, o), std::invalid_argument);
  o = {};
  o.window_m = 0.0;
  EXPECT_THROW(cosIncidence(scan, o), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::slam2d
