// Laser2dRobot: simulated 2D-laser robot producing LaserScan2D messages.

#include "client/laser2d_robot.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace rmap::client {
namespace {

/// Planar pose (x, y, yaw) of a level 3D pose.
Eigen::Vector3d planar(const Eigen::Isometry3d& pose) {
  const Eigen::Vector3d x_axis = pose.linear().col(0);
  return {pose.translation().x(), pose.translation().y(), std::atan2(x_axis.y(), x_axis.x())};
}

Eigen::Vector3d compose(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double c = std::cos(a.z()), s = std::sin(a.z());
  return {a.x() + c * b.x() - s * b.y(), a.y() + s * b.x() + c * b.y(),
          std::remainder(a.z() + b.z(), 2 * std::numbers::pi)};
}

Eigen::Vector3d between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double c = std::cos(a.z()), s = std::sin(a.z());
  const Eigen::Vector2d d = b.head<2>() - a.head<2>();
  return {c * d.x() + s * d.y(), -s * d.x() + c * d.y(), std::remainder(b.z() - a.z(), 2 * std::numbers::pi)};
}

}  // namespace

void Laser2dRobotOptions::validate() const {
  laser.validate();
  if (sensor_name.empty()) throw std::invalid_argument("laser2d robot: sensor_name must not be empty");
  if (!std::isfinite(mount_forward_m)) throw std::invalid_argument("laser2d robot: mount_forward_m must be finite");
  if (!(mount_height_m > 0.0) || !std::isfinite(mount_height_m)) {
    throw std::invalid_argument("laser2d robot: mount_height_m must be finite and > 0");
  }
  for (const double sigma : {odometry_forward_sigma, odometry_lateral_sigma_per_m, odometry_heading_sigma_rad}) {
    if (!(sigma >= 0.0) || !std::isfinite(sigma)) {
      throw std::invalid_argument("laser2d robot: odometry sigmas must be finite and >= 0");
    }
  }
}

Laser2dRobot::Laser2dRobot(const sim::VoxelWorld& world, std::vector<Eigen::Isometry3d> laser_tour,
                           Laser2dRobotOptions options, uint64_t seed)
    : world_(&world), tour_(std::move(laser_tour)), options_(std::move(options)) {
  std::seed_seq odometry_seeds{seed, uint64_t{1}}, scan_seeds{seed, uint64_t{2}};
  odometry_rng_.seed(odometry_seeds);
  scan_rng_.seed(scan_seeds);
  options_.validate();
  if (tour_.empty()) throw std::invalid_argument("laser2d robot: the tour has no pose");
}

rmap::v1::SensorDescription Laser2dRobot::sensor() const {
  rmap::v1::SensorDescription sensor;
  sensor.set_name(options_.sensor_name);
  sensor.set_kind(rmap::v1::SensorDescription::LASER_2D);
  sensor.set_model(options_.laser.name);
  sensor.mutable_mount()->mutable_position_m()->set_x(options_.mount_forward_m);
  sensor.mutable_mount()->mutable_position_m()->set_z(options_.mount_height_m);
  sensor.mutable_mount()->mutable_orientation()->set_w(1.0);
  return sensor;
}

Eigen::Isometry3d Laser2dRobot::tourPose(uint64_t step) const {
  const uint64_t n = tour_.size();
  if (n == 1) return tour_[0];
  const uint64_t i = step % (2 * (n - 1));
  if (i < n) return tour_[i];
  // On the way back the robot faces where it goes.
  return tour_[2 * (n - 1) - i] * Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitZ());
}

Eigen::Isometry3d Laser2dRobot::drive() {
  const Eigen::Isometry3d laser_pose = tourPose(step_);
  const Eigen::Vector3d mount_inverse(-options_.mount_forward_m, 0.0, 0.0);
  const Eigen::Vector3d truth = compose(planar(laser_pose), mount_inverse);
  if (step_ == 0) {
    odometry_ = truth;  // odometry in the map frame: the SLAM's frame is the world's
  } else {
    std::normal_distribution<double> unit(0.0, 1.0);
    const Eigen::Vector3d motion = between(last_truth_, truth);
    const double d = motion.head<2>().norm();
    const double forward = unit(odometry_rng_), lateral = unit(odometry_rng_), heading = unit(odometry_rng_);
    const Eigen::Vector3d measured(motion.x() * (1 + options_.odometry_forward_sigma * forward),
                                   motion.y() + options_.odometry_lateral_sigma_per_m * d * lateral,
                                   motion.z() + options_.odometry_heading_sigma_rad * heading);
    odometry_ = compose(odometry_, measured);
  }
  last_truth_ = truth;
  ++step_;
  return laser_pose;
}

void Laser2dRobot::skip(uint64_t steps) {
  for (uint64_t k = 0; k < steps; ++k) drive();
}

Laser2dStep Laser2dRobot::next() {
  Laser2dStep out;
  out.laser_pose_world = drive();
  out.base_truth = last_truth_;
  const sim::Laser2dScan scan = sim::simulateLaser2d(*world_, out.laser_pose_world, options_.laser, scan_rng_);
  rmap::v1::LaserScan2D& m = out.scan;
  m.set_sensor(options_.sensor_name);
  m.set_angle_min_rad(scan.angle_min_rad);
  m.set_angle_increment_rad(scan.angle_increment_rad);
  m.set_range_min_m(scan.range_min_m);
  m.set_range_max_m(scan.range_max_m);
  m.mutable_ranges_m()->Reserve(static_cast<int>(scan.ranges_m.size()));
  m.mutable_intensities()->Reserve(static_cast<int>(scan.intensities.size()));
  for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
    // The simulator reads "too close" as −inf; the protocol has only +inf for no return.
    m.add_ranges_m(std::isfinite(scan.ranges_m[i]) ? scan.ranges_m[i] : INFINITY);
    m.add_intensities(scan.intensities[i]);
  }
  m.mutable_odometry()->set_x_m(odometry_.x());
  m.mutable_odometry()->set_y_m(odometry_.y());
  m.mutable_odometry()->set_theta_rad(odometry_.z());
  return out;
}

void extendMarkersToLaserPlane(sim::VoxelWorld& world, const sim::BuildingLayout& layout, double floor_height_m,
                               double laser_height_m) {
  for (const Eigen::AlignedBox3d& m : layout.markers) {
    const double floor_z = std::floor(m.min().z() / floor_height_m) * floor_height_m;
    const double z = floor_z + laser_height_m;
    // From the strip itself to the laser's plane, so the strip stays one piece.
    world.fillBox(Eigen::AlignedBox3d(Eigen::Vector3d(m.min().x(), m.min().y(), std::min(m.min().z(), z - 0.3)),
                                      Eigen::Vector3d(m.max().x(), m.max().y(), std::max(m.max().z(), z + 0.3))),
                  0.95f);
  }
}

}  // namespace rmap::client
