#include "sim/lidar.h"

#include "test_worlds.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace rmap::sim {
namespace {

using Eigen::Vector3d;

using test::at;

VoxelWorld closedRoom() { return test::closedRoom(4.0, 0.5f); }

/// A wide wall x ∈ [15, 15.3] of reflectivity rho.
VoxelWorld wall(float rho) {
  VoxelWorld w = VoxelWorld::covering(box(-1, -25, -5, 16, 25, 5), 0.1);
  w.fillBox(box(15, -25, -5, 15.3, 25, 5), rho);
  return w;
}

/// 65 rings so ring 32 is level; no noise so intensities follow the model exactly.
LidarModel levelRingModel() {
  LidarModel m;
  m.rings = 65;
  m.range_noise_sigma_m = 0.0;
  m.intensity.noise_rel_sigma = 0.0;
  return m;
}

/// Intensity of one beam (−1 when it has no return).
float beamIntensity(const LidarScan& scan, uint32_t beam) {
  for (size_t i = 0; i < scan.beam_ids.size(); ++i) {
    if (scan.beam_ids[i] == beam) return scan.intensities[i];
  }
  return -1.0f;
}

TEST(Lidar, BeamPattern) {
  LidarModel m;
  const auto dirs = lidarBeamDirections(m);
  ASSERT_EQ(dirs.size(), 64u * 1024u);
  constexpr double kDeg = std::numbers::pi / 180.0;
  EXPECT_NEAR(std::asin(dirs[0].z()), -22.5 * kDeg, 1e-12);
  EXPECT_NEAR(std::asin(dirs[63 * 1024].z()), 22.5 * kDeg, 1e-12);
  EXPECT_NEAR(std::atan2(dirs[256].y(), dirs[256].x()), std::numbers::pi / 2, 1e-12);  // column 256: +y
  for (const Vector3d& d : dirs) ASSERT_NEAR(d.norm(), 1.0, 1e-12);
}

TEST(Lidar, ClosedRoomReturnsEveryBeamWithTheConfiguredNoise) {
  const VoxelWorld room = closedRoom();
  LidarModel m;
  m.range_noise_sigma_m = 0.02;
  std::mt19937_64 rng(11);
  const Eigen::Isometry3d pose = at(0.3, -0.7, 1.6, 0.4);
  const LidarScan scan = simulateLidar(room, pose, m, rng);
  ASSERT_EQ(scan.points_m.size(), static_cast<size_t>(m.rings * m.columns));
  ASSERT_EQ(scan.intensities.size(), scan.points_m.size());
  ASSERT_EQ(scan.true_ranges_m.size(), scan.points_m.size());
  ASSERT_EQ(scan.beam_ids.size(), scan.points_m.size());
  EXPECT_TRUE(scan.sensor_origin_m.isApprox(Eigen::Vector3f(0.3f, -0.7f, 1.6f)));
  double sum = 0.0, sum2 = 0.0;
  for (size_t i = 0; i < scan.points_m.size(); ++i) {
    const double measured = (scan.points_m[i] - scan.sensor_origin_m).norm();
    const double residual = measured - scan.true_ranges_m[i];
    sum += residual;
    sum2 += residual * residual;
    EXPECT_NEAR(scan.reflectivities[i], 0.5f, 1.0f / 255);
  }
  const double n = static_cast<double>(scan.points_m.size());
  EXPECT_NEAR(sum / n, 0.0, 0.0005);
  EXPECT_NEAR(std::sqrt(sum2 / n - (sum / n) * (sum / n)), 0.02, 0.02 * 0.03);
  // Noise-free ranges are the ray-cast distances to the shell.
  const auto dirs = lidarBeamDirections(m);
  for (size_t i = 0; i < scan.points_m.size(); i += 997) {
    const Vector3d dir = pose.linear() * dirs[scan.beam_ids[i]];
    const auto hit = room.castRay(pose.translation(), dir.normalized(), m.max_range_m);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(scan.true_ranges_m[i], hit->range_m, 1e-5);
  }
}

TEST(Lidar, PointCountIsBeamsMinusMisses) {
  // Only a floor: upward beams and far downward ones have no return.
  VoxelWorld floor = VoxelWorld::covering(box(-20, -20, -0.2, 20, 20, 3), 0.1);
  floor.fillBox(box(-20, -20, -0.2, 20, 20, 0), 0.3f);
  LidarModel m;
  m.max_range_m = 10.0;
  const Eigen::Isometry3d pose = at(0.05, 0.05, 1.5);
  std::mt19937_64 rng(5);
  const LidarScan scan = simulateLidar(floor, pose, m, rng);
  size_t expected = 0;
  for (const Vector3d& d : lidarBeamDirections(m)) {
    const auto hit = floor.castRay(pose.translation(), d, m.max_range_m);
    expected += hit && hit->range_m >= m.min_range_m;
  }
  EXPECT_GT(expected, 0u);
  EXPECT_LT(expected, static_cast<size_t>(m.rings * m.columns));
  EXPECT_EQ(scan.points_m.size(), expected);
  for (const auto& p : scan.points_m) EXPECT_NEAR(p.z(), 0.0f, 0.06f);

  // With report_no_return every beam yields a point; misses at max range + 1 m, intensity 0.
  m.report_no_return = true;
  const LidarScan full = simulateLidar(floor, pose, m, rng);
  ASSERT_EQ(full.points_m.size(), static_cast<size_t>(m.rings * m.columns));
  size_t misses = 0;
  for (size_t i = 0; i < full.points_m.size(); ++i) {
    if (!std::isinf(full.true_ranges_m[i])) continue;
    ++misses;
    EXPECT_EQ(full.intensities[i], 0.0f);
    EXPECT_NEAR((full.points_m[i] - full.sensor_origin_m).norm(), m.max_range_m + 1.0, 1e-4);
  }
  EXPECT_EQ(misses, full.points_m.size() - expected);
}

TEST(Lidar, SurfacesInsideMinRangeGiveNoReturn) {
  const VoxelWorld w = wall(0.5f);
  LidarModel m = levelRingModel();
  m.min_range_m = 0.3;
  std::mt19937_64 rng(1);
  const uint32_t forward = 32 * 1024;
  EXPECT_LT(beamIntensity(simulateLidar(w, at(14.8, 0.05, 0.05), m, rng), forward), 0.0f);  // 0.2 m away
  EXPECT_GT(beamIntensity(simulateLidar(w, at(14.6, 0.05, 0.05), m, rng), forward), 0.0f);  // 0.4 m away
}

TEST(Lidar, IntensityFallsWithRangeAndIncidenceAndScalesWithReflectivity) {
  const LidarModel m = levelRingModel();
  std::mt19937_64 rng(2);
  const uint32_t forward = 32 * 1024, diagonal = 32 * 1024 + 128;  // azimuth 0 and 45°
  const VoxelWorld grey = wall(0.4f);

  // Same reflectivity, normal incidence: farther is weaker (beyond the near zone).
  const float at3 = beamIntensity(simulateLidar(grey, at(12.05, 0.05, 0.05), m, rng), forward);
  const float at6 = beamIntensity(simulateLidar(grey, at(9.05, 0.05, 0.05), m, rng), forward);
  const float at12 = beamIntensity(simulateLidar(grey, at(3.05, 0.05, 0.05), m, rng), forward);
  EXPECT_GT(at3, at6);
  EXPECT_GT(at6, at12);
  EXPECT_NEAR(at6, m.intensity.expected(0.4, 5.95, 1.0), 1e-3);

  // Same range 4√2 m: the 45° beam of a sensor 4 m from the wall is weaker than a perpendicular one.
  const double d = 4.0 * std::sqrt(2.0);
  const float oblique = beamIntensity(simulateLidar(grey, at(11.0, 0.05, 0.05), m, rng), diagonal);
  const float normal = beamIntensity(simulateLidar(grey, at(15.0 - d, 0.05, 0.05), m, rng), forward);
  EXPECT_GT(normal, oblique);
  EXPECT_NEAR(oblique / normal, std::pow(std::sqrt(0.5), m.intensity.incidence_exponent), 1e-3);

  // Proportional to reflectivity (0.2 and 0.8 quantise exactly).
  const float dark = beamIntensity(simulateLidar(wall(0.2f), at(9.05, 0.05, 0.05), m, rng), forward);
  const float bright = beamIntensity(simulateLidar(wall(0.8f), at(9.05, 0.05, 0.05), m, rng), forward);
  EXPECT_NEAR(bright / dark, 4.0, 1e-4);
}

TEST(Lidar, PointsAreInTheWorldFrame) {
  const VoxelWorld w = wall(0.5f);
  LidarModel m = levelRingModel();
  std::mt19937_64 rng(3);
  // Yawed by 90°, column 768 (azimuth 270°) looks along world +x at the wall.
  const LidarScan scan = simulateLidar(w, at(5.05, 0.05, 0.05, std::numbers::pi / 2), m, rng);
  bool found = false;
  for (size_t i = 0; i < scan.beam_ids.size(); ++i) {
    if (scan.beam_ids[i] != 32 * 1024 + 768) continue;
    found = true;
    EXPECT_NEAR(scan.points_m[i].x(), 15.0f, 1e-4f);
    EXPECT_NEAR(scan.points_m[i].y(), 0.05f, 1e-4f);
  }
  EXPECT_TRUE(found);
}

TEST(Lidar, DeterministicGivenASeed) {
  const VoxelWorld room = closedRoom();
  LidarModel m;
  m.rings = 16;
  m.columns = 256;
  std::mt19937_64 a(42), b(42), c(43);
  const LidarScan sa = simulateLidar(room, at(0, 0, 1), m, a);
  const LidarScan sb = simulateLidar(room, at(0, 0, 1), m, b);
  const LidarScan sc = simulateLidar(room, at(0, 0, 1), m, c);
  ASSERT_EQ(sa.points_m.size(), sb.points_m.size());
  for (size_t i = 0; i < sa.points_m.size(); ++i) {
    ASSERT_EQ(sa.points_m[i], sb.points_m[i]);
    ASSERT_EQ(sa.intensities[i], sb.intensities[i]);
  }
  EXPECT_NE(sa.points_m[0], sc.points_m[0]);
}

TEST(Lidar, RejectsBadModels) {
  const VoxelWorld room = closedRoom();
  std::mt19937_64 rng(0);
  LidarModel m;
  m.rings = 0;
  EXPECT_THROW(simulateLidar(room, at(0, 0, 1), m, rng), std::invalid_argument);
  m = LidarModel{};
  m.max_range_m = 0.1;
  EXPECT_THROW(simulateLidar(room, at(0, 0, 1), m, rng), std::invalid_argument);
  m = LidarModel{};
  m.fov_up_deg = -30.0;
  EXPECT_THROW(simulateLidar(room, at(0, 0, 1), m, rng), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::sim
