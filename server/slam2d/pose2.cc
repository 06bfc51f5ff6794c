#include "slam2d/pose2.h"

#include <numbers>

namespace rmap::slam2d {

double normalizeAngle(double angle_rad) {
  double a = std::remainder(angle_rad, 2.0 * std::numbers::pi);
  if (a <= -std::numbers::pi) a += 2.0 * std::numbers::pi;
  return a;
}

Eigen::Vector2d Pose2::operator*(const Eigen::Vector2d& p) const {
  const double c = std::cos(theta_rad), s = std::sin(theta_rad);
  return {x_m + c * p.x() - s * p.y(), y_m + s * p.x() + c * p.y()};
}

Pose2 Pose2::operator*(const Pose2& b) const {
  const Eigen::Vector2d t = (*this) * b.translation();
  return {t.x(), t.y(), normalizeAngle(theta_rad + b.theta_rad)};
}

Pose2 Pose2::inverse() const {
  const double c = std::cos(theta_rad), s = std::sin(theta_rad);
  return {-(c * x_m + s * y_m), -(-s * x_m + c * y_m), normalizeAngle(-theta_rad)};
}

Pose2 between(const Pose2& a, const Pose2& b) { return a.inverse() * b; }

Eigen::Isometry3d planarIsometry(const Pose2& p, double z_m) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::AngleAxisd(p.theta_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  out.translation() = Eigen::Vector3d(p.x_m, p.y_m, z_m);
  return out;
}

}  // namespace rmap::slam2d
