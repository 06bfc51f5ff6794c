#pragma once
/// @file laser2d_robot.h
/// A simulated wheeled robot with a planar 2D laser: drives a tour of laser
/// poses back and forth and turns each step into a LaserScan2D (ranges,
/// intensities, noisy odometry) plus the ground truth it was made from. The
/// one source of 2D scans for the sim feed and the 2D SLAM integration test.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "rmap/v1/robot_stream.pb.h"
#include "sim/building.h"
#include "sim/laser2d.h"
#include "sim/voxel_world.h"

namespace rmap::client {

struct Laser2dRobotOptions {
  sim::Laser2dModel laser = sim::Laser2dModel::sickLike();
  std::string sensor_name = "laser";
  double mount_forward_m = 0.15;  ///< laser ahead of the robot base, metres
  double mount_height_m = 1.0;    ///< laser above the base (the floor), metres; the tour's sensor height
  /// Wheel odometry drift per step: relative error of the forward motion,
  /// lateral error per metre driven, and heading error (rad, absolute).
  double odometry_forward_sigma = 0.05;
  double odometry_lateral_sigma_per_m = 0.02;
  double odometry_heading_sigma_rad = 0.02;

  /// @throws std::invalid_argument naming the first bad parameter
  void validate() const;
};

/// One step of the robot: the message body and what it was made from.
struct Laser2dStep {
  rmap::v1::LaserScan2D scan;  ///< sensor, ranges, intensities, odometry; stamp_ns left 0 for the sender
  Eigen::Vector3d base_truth;  ///< robot base (x_m, y_m, yaw_rad) in the map frame
  Eigen::Isometry3d laser_pose_world;  ///< where the scan was simulated
};

class Laser2dRobot {
 public:
  /// @param laser_tour  laser poses (level, x along travel, at mount_height_m
  ///        above the floor, e.g. from sim::planTrajectory); driven forwards,
  ///        then backwards facing the other way, and so on, so the motion
  ///        (and the odometry) stays continuous however many steps are taken
  /// @param seed  odometry and sensor noise (deterministic in it; the two
  ///        come from separate streams, so skip() needs no scan)
  /// @throws std::invalid_argument for bad options or an empty tour
  Laser2dRobot(const sim::VoxelWorld& world, std::vector<Eigen::Isometry3d> laser_tour, Laser2dRobotOptions options,
               uint64_t seed);

  /// The LASER_2D description for the Hello (name, model, mount).
  rmap::v1::SensorDescription sensor() const;

  /// Simulates the next step. The first odometry pose is the true base pose
  /// (odometry in the map frame, as robots sharing a map must send it); each
  /// later one adds the true motion with drift.
  Laser2dStep next();

  /// Drives `steps` steps without scanning: a robot resuming after a restart
  /// whose first steps the server already holds continues from there, with
  /// the same odometry as if it had never stopped.
  void skip(uint64_t steps);

  uint64_t steps() const { return step_; }

 private:
  Eigen::Isometry3d tourPose(uint64_t step) const;
  /// Moves to the next tour pose, integrating odometry; returns the laser pose.
  Eigen::Isometry3d drive();

  const sim::VoxelWorld* world_;  ///< not owned; outlives the robot
  std::vector<Eigen::Isometry3d> tour_;
  Laser2dRobotOptions options_;
  std::mt19937_64 odometry_rng_;
  std::mt19937_64 scan_rng_;
  uint64_t step_ = 0;
  Eigen::Vector3d last_truth_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d odometry_ = Eigen::Vector3d::Zero();
};

/// Extends the building's reflective tape markers vertically down or up to
/// the plane of 2D lasers mounted `laser_height_m` above each storey's floor
/// (to ±0.3 m around it, reflectivity 0.95), so the lasers see them. layout.markers keep
/// their footprint (x, y).
void extendMarkersToLaserPlane(sim::VoxelWorld& world, const sim::BuildingLayout& layout, double floor_height_m,
                               double laser_height_m);

}  // namespace rmap::client
