#pragma once
/// @file lidar.h
/// Spinning multi-ring 3D lidar (Ouster/Velodyne-like) simulated by ray
/// casting through a VoxelWorld. The scan is taken at one pose (no motion
/// distortion).
///
/// Sensor frame: x forward, y left, z up. Ring i (0 = lowest) has elevation
/// fov_down + i·(fov_up − fov_down)/(rings − 1) (the mean of both for one
/// ring); column j has azimuth 2π·j/columns counter-clockwise from +x.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <random>
#include <vector>

#include "sim/intensity.h"
#include "sim/voxel_world.h"

namespace rmap::sim {

struct LidarModel {
  int rings = 64;                    ///< ≥ 1
  int columns = 1024;                ///< ≥ 1
  double fov_up_deg = 22.5;          ///< elevation of the top ring, degrees, ≤ 90
  double fov_down_deg = -22.5;       ///< elevation of the bottom ring, degrees, ≥ −90, ≤ fov_up_deg
  double max_range_m = 30.0;         ///< metres, > min_range_m; hits at range ≥ this are misses
  double min_range_m = 0.3;          ///< metres, ≥ 0; closer surfaces blind the beam (no return)
  double range_noise_sigma_m = 0.01; ///< metres, ≥ 0; Gaussian noise added to the range
  /// Emit missed beams as a point at max_range_m + 1 m along the beam with
  /// intensity 0, reflectivity 0 and true range +inf (a free-space ray for
  /// mappers that clear along no-return beams).
  bool report_no_return = false;
  IntensityModel intensity;

  /// @throws std::invalid_argument naming the first bad parameter
  void validate() const;
};

/// One scan; arrays are parallel, one entry per returned beam, in beam order
/// (ring-major: beam id = ring·columns + column).
struct LidarScan {
  Eigen::Vector3f sensor_origin_m;      ///< world frame
  std::vector<Eigen::Vector3f> points_m;///< world frame, measured (noisy) range along the beam
  std::vector<float> intensities;       ///< counts, see IntensityModel
  std::vector<float> true_ranges_m;     ///< noise-free range to the surface (+inf for no-return points)
  std::vector<float> reflectivities;    ///< ground-truth ρ of the surface hit (0 for no-return points)
  std::vector<uint32_t> beam_ids;       ///< ring·columns + column
};

/// Unit beam directions in the sensor frame, indexed by beam id.
std::vector<Eigen::Vector3d> lidarBeamDirections(const LidarModel& model);

/// Simulates one scan.
/// @param sensor_pose_world  sensor frame → world frame
/// @param rng  source of range and intensity noise; draws happen in beam order
///             (range, then intensity, for each returned beam), so a seed fixes the scan
/// @throws std::invalid_argument for a bad model
LidarScan simulateLidar(const VoxelWorld& world, const Eigen::Isometry3d& sensor_pose_world, const LidarModel& model,
                        std::mt19937_64& rng);

}  // namespace rmap::sim
