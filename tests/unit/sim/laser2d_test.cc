#include "sim/laser2d.h"

#include "test_worlds.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace rmap::sim {
namespace {

using Eigen::Vector3d;

using test::at;

/// Square room [−5, 5]² × [0, 3], walls of reflectivity 0.6.
VoxelWorld laserRoom() { return test::closedRoom(3.0, 0.6f); }

TEST(Laser2d, GeometryAndConventions) {
  const VoxelWorld w = laserRoom();
  Laser2dModel m = Laser2dModel::hokuyoLike();
  std::mt19937_64 rng(1);
  const Laser2dScan scan = simulateLaser2d(w, at(0.0, 0.0, 1.0), m, rng);
  ASSERT_EQ(scan.ranges_m.size(), 1081u);
  ASSERT_EQ(scan.intensities.size(), 1081u);
  EXPECT_EQ(scan.model_name, "hokuyo_like");
  EXPECT_NEAR(scan.angle_min_rad, -0.75 * std::numbers::pi, 1e-6);
  EXPECT_NEAR(scan.angle_max_rad, 0.75 * std::numbers::pi, 1e-6);
  EXPECT_NEAR(scan.angle_increment_rad, 0.25 * std::numbers::pi / 180, 1e-7);
  EXPECT_EQ(scan.range_max_m, 30.0f);
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double a = scan.angle_min_rad + i * double(scan.angle_increment_rad);
    const double expected = 5.0 / std::max(std::abs(std::cos(a)), std::abs(std::sin(a)));
    ASSERT_NEAR(scan.true_ranges_m[i], expected, 1e-4) << "beam " << i;
    ASSERT_NEAR(scan.ranges_m[i], expected, 0.06) << "beam " << i;
    ASSERT_GT(scan.intensities[i], 0.0f);
    ASSERT_NEAR(scan.reflectivities[i], 0.6f, 1.0f / 255);
  }
}

TEST(Laser2d, RangeNoiseHasTheConfiguredSigma) {
  const VoxelWorld w = laserRoom();
  Laser2dModel m = Laser2dModel::sickLike();
  m.range_noise_sigma_m = 0.03;
  std::mt19937_64 rng(2);
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int scan_index = 0; scan_index < 40; ++scan_index) {
    const Laser2dScan scan = simulateLaser2d(w, at(0.4, -0.3, 1.0), m, rng);
    for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
      const double r = scan.ranges_m[i] - scan.true_ranges_m[i];
      sum += r;
      sum2 += r * r;
      ++n;
    }
  }
  EXPECT_NEAR(sum / n, 0.0, 0.001);
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.03, 0.03 * 0.04);
}

TEST(Laser2d, NoReturnAndTooCloseUseInfinities) {
  // A single post x ∈ [0.5, 0.55]; the Hokuyo-like minimum range is 0.1 m.
  VoxelWorld w = VoxelWorld::covering(box(-1, -1, -1, 1, 1, 1), 0.05);
  w.fillBox(box(0.5, -0.05, -1, 0.55, 0.05, 1), 0.5f);
  Laser2dModel m = Laser2dModel::hokuyoLike();
  std::mt19937_64 rng(3);
  const int forward = (m.beams - 1) / 2;  // angle 0
  Laser2dScan scan = simulateLaser2d(w, at(0.0, 0.0, 0.0), m, rng);
  EXPECT_NEAR(scan.ranges_m[forward], 0.5f, 0.05f);
  EXPECT_EQ(scan.ranges_m[0], std::numeric_limits<float>::infinity());  // nothing behind
  EXPECT_EQ(scan.intensities[0], 0.0f);
  scan = simulateLaser2d(w, at(0.45, 0.0, 0.0), m, rng);  // 5 cm from the post, below 0.1 m
  EXPECT_EQ(scan.ranges_m[forward], -std::numeric_limits<float>::infinity());
  EXPECT_EQ(scan.intensities[forward], 0.0f);
  EXPECT_NEAR(scan.true_ranges_m[forward], 0.05f, 1e-4f);
}

TEST(Laser2d, PresetsDiffer) {
  const Laser2dModel sick = Laser2dModel::sickLike(), hokuyo = Laser2dModel::hokuyoLike();
  EXPECT_NE(sick.name, hokuyo.name);
  EXPECT_NE(sick.beams, hokuyo.beams);
  EXPECT_NE(sick.intensity.range_exponent, hokuyo.intensity.range_exponent);
  EXPECT_NE(sick.intensity.incidence_exponent, hokuyo.intensity.incidence_exponent);
  // Their responses differ in shape, not just scale: the ratio changes with range and angle.
  const double near_ratio = sick.intensity.expected(0.5, 3.0, 1.0) / hokuyo.intensity.expected(0.5, 3.0, 1.0);
  const double far_ratio = sick.intensity.expected(0.5, 12.0, 1.0) / hokuyo.intensity.expected(0.5, 12.0, 1.0);
  const double slant_ratio = sick.intensity.expected(0.5, 3.0, 0.5) / hokuyo.intensity.expected(0.5, 3.0, 0.5);
  EXPECT_GT(far_ratio / near_ratio, 2.0);
  EXPECT_GT(slant_ratio / near_ratio, 1.3);

  // And in simulated scans of the same room from the same pose.
  const VoxelWorld w = laserRoom();
  std::mt19937_64 rng(4);
  const Laser2dScan a = simulateLaser2d(w, at(-3.0, 0.0, 1.0), sick, rng);
  const Laser2dScan b = simulateLaser2d(w, at(-3.0, 0.0, 1.0), hokuyo, rng);
  EXPECT_EQ(a.ranges_m.size(), 541u);
  const float a_near = a.intensities[(a.ranges_m.size() - 1) / 2 + 180];  // +90°: wall 5 m away
  const float b_near = b.intensities[(b.ranges_m.size() - 1) / 2 + 360];
  const float a_far = a.intensities[(a.ranges_m.size() - 1) / 2];  // 0°: wall 8 m away
  const float b_far = b.intensities[(b.ranges_m.size() - 1) / 2];
  EXPECT_GT((a_far / b_far) / (a_near / b_near), 1.2f);
}

TEST(Laser2d, RejectsBadModels) {
  const VoxelWorld w = laserRoom();
  std::mt19937_64 rng(5);
  Laser2dModel m;
  m.beams = 1;
  EXPECT_THROW(simulateLaser2d(w, at(0, 0, 1), m, rng), std::invalid_argument);
  m = Laser2dModel{};
  m.fov_deg = 400;
  EXPECT_THROW(simulateLaser2d(w, at(0, 0, 1), m, rng), std::invalid_argument);
  m = Laser2dModel{};
  m.intensity.gain = -1;
  EXPECT_THROW(simulateLaser2d(w, at(0, 0, 1), m, rng), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::sim
