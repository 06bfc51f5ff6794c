#pragma once
/// @file sim_scans.h
/// Test helper: simulated building, robot tour and 2D laser scans in the
/// LaserScan form the SLAM takes (clients/sim).

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "sim/building.h"
#include "sim/laser2d.h"
#include "sim/trajectory.h"
#include "slam2d/laser_scan.h"
#include "slam2d/pose2.h"

namespace rmap::slam2d::testing {

/// A one-storey building (same seed → same world).
inline sim::VoxelWorld simBuilding(uint64_t seed = 7) {
  sim::BuildingOptions options;
  options.voxel_m = 0.05;
  return sim::makeBuilding(options, seed);
}

/// Planar pose of a level sensor pose.
inline Pose2 planar(const Eigen::Isometry3d& pose) {
  const Eigen::Vector3d x_axis = pose.linear().col(0);
  return {pose.translation().x(), pose.translation().y(), std::atan2(x_axis.y(), x_axis.x())};
}

/// Sensor at a planar pose, `height_m` above the floor.
inline Eigen::Isometry3d sensorAt(const Pose2& p, double height_m = 1.0) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(p.x_m, p.y_m, height_m);
  t.linear() = Eigen::AngleAxisd(p.theta_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return t;
}

/// A simulated scan as LaserScan (sensor at the robot base: identity mount).
inline LaserScan toLaserScan(const sim::Laser2dScan& s, int64_t stamp_ns = 0) {
  LaserScan scan;
  scan.stamp_ns = stamp_ns;
  scan.model = s.model_name;
  scan.range_min_m = s.range_min_m;
  scan.range_max_m = s.range_max_m;
  scan.ranges_m = s.ranges_m;
  scan.intensities = s.intensities;
  scan.angles_rad.resize(s.ranges_m.size());
  for (size_t i = 0; i < s.ranges_m.size(); ++i)
    scan.angles_rad[i] = s.angle_min_rad + static_cast<float>(i) * s.angle_increment_rad;
  return scan;
}

inline LaserScan simScan(const sim::VoxelWorld& world, const Pose2& robot, const sim::Laser2dModel& model,
                         std::mt19937_64& rng, int64_t stamp_ns = 0) {
  return toLaserScan(sim::simulateLaser2d(world, sensorAt(robot), model, rng), stamp_ns);
}

/// A tour of `poses` planar poses at most `step_m` apart through the building.
inline std::vector<Pose2> simTour(const sim::VoxelWorld& world, int poses, double step_m, uint64_t seed = 3) {
  sim::TrajectoryOptions options;
  options.num_poses = poses;
  options.step_m = step_m;
  options.max_step_m = std::min(options.max_step_m, step_m - 0.02);
  std::vector<Pose2> tour;
  for (const Eigen::Isometry3d& p : sim::planTrajectory(world, options, seed)) tour.push_back(planar(p));
  return tour;
}

/// The tour with in-place turns inserted so the heading changes by at most
/// max_turn_rad between poses, as a robot turns while its laser keeps scanning
/// (the planned tour turns its heading at once at path corners).
inline std::vector<Pose2> smoothTurns(const std::vector<Pose2>& tour, double max_turn_rad) {
  std::vector<Pose2> out;
  for (const Pose2& p : tour) {
    if (!out.empty()) {
      const Pose2 last = out.back();
      const double turn = normalizeAngle(p.theta_rad - last.theta_rad);
      const int steps = static_cast<int>(std::ceil(std::abs(turn) / max_turn_rad));
      for (int i = 1; i < steps; ++i) out.push_back({last.x_m, last.y_m, normalizeAngle(last.theta_rad + turn * i / steps)});
    }
    out.push_back(p);
  }
  return out;
}

}  // namespace rmap::slam2d::testing
