#pragma once
/// @file pose2.h
/// Planar rigid poses (x, y in metres, theta in radians, counter-clockwise),
/// with the composition rules every part of 2D SLAM and its scoring shares.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace rmap::slam2d {

/// Wraps an angle to (−π, π].
double normalizeAngle(double angle_rad);

struct Pose2 {
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;

  Eigen::Vector2d translation() const { return {x_m, y_m}; }
  /// Maps a point from this pose's frame into the parent frame.
  Eigen::Vector2d operator*(const Eigen::Vector2d& p) const;
  /// Composition a ⊕ b: b expressed in a's frame, result in a's parent frame.
  Pose2 operator*(const Pose2& b) const;
  Pose2 inverse() const;
  bool isFinite() const { return std::isfinite(x_m) && std::isfinite(y_m) && std::isfinite(theta_rad); }
};

/// The motion from a to b in a's frame: a⁻¹ ⊕ b.
Pose2 between(const Pose2& a, const Pose2& b);

/// The planar pose in 3D: turned about z, at height z_m (metres).
Eigen::Isometry3d planarIsometry(const Pose2& p, double z_m = 0.0);

}  // namespace rmap::slam2d
