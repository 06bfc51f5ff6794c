#pragma once
/// @file laser2d.h
/// Planar 2D laser scanner (SICK/Hokuyo-like) simulated by ray casting
/// through a VoxelWorld, with the LaserScan conventions of ROS REP 117.
///
/// Beams lie in the sensor's x-y plane; beam i has angle angle_min + i·increment
/// counter-clockwise from +x, with angle_min = −fov/2 and the last beam at +fov/2.
/// Range conventions: no surface within max_range_m → +inf; a surface closer
/// than min_range_m → −inf; both have intensity 0.

#include <Eigen/Geometry>
#include <random>
#include <string>
#include <vector>

#include "sim/intensity.h"
#include "sim/voxel_world.h"

namespace rmap::sim {

struct Laser2dModel {
  std::string name = "generic";       ///< label carried into scans (calibration is per scanner model)
  double fov_deg = 270.0;             ///< degrees, (0, 360]
  int beams = 1081;                   ///< ≥ 2
  double max_range_m = 30.0;          ///< metres, > min_range_m
  double min_range_m = 0.05;          ///< metres, ≥ 0
  double range_noise_sigma_m = 0.01;  ///< metres, ≥ 0
  IntensityModel intensity;

  /// @throws std::invalid_argument naming the first bad parameter
  void validate() const;

  /// SICK LMS1xx-like: 541 beams (0.5°), 25 m, 12 mm noise; receiver with
  /// strong automatic gain: intensity falls slowly with range (e = 1.2),
  /// weakly with incidence (k = 0.6), short blind zone, large count range.
  static Laser2dModel sickLike();
  /// Hokuyo UTM-30LX-like: 1081 beams (0.25°), 30 m, 10 mm noise; steep
  /// response: faster than inverse-square fall-off (e = 2.2), strong
  /// incidence dependence (k = 1.5), long near-range drop, noisier counts.
  static Laser2dModel hokuyoLike();
};

struct Laser2dScan {
  std::string model_name;
  float angle_min_rad = 0.0f;
  float angle_max_rad = 0.0f;
  float angle_increment_rad = 0.0f;
  float range_min_m = 0.0f;
  float range_max_m = 0.0f;
  std::vector<float> ranges_m;        ///< measured, per beam; ±inf as described above
  std::vector<float> intensities;     ///< counts, per beam
  std::vector<float> true_ranges_m;   ///< noise-free range per beam (+inf when nothing within max range)
  std::vector<float> reflectivities;  ///< ground-truth ρ of the surface hit, 0 without a return
};

/// Simulates one scan.
/// @param sensor_pose_world  sensor frame → world frame
/// @param rng  noise source; per returned beam one range draw then one intensity draw
/// @throws std::invalid_argument for a bad model
Laser2dScan simulateLaser2d(const VoxelWorld& world, const Eigen::Isometry3d& sensor_pose_world,
                            const Laser2dModel& model, std::mt19937_64& rng);

}  // namespace rmap::sim
