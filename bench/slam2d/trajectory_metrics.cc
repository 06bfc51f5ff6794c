#include "slam2d/trajectory_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace rmap::bench {
namespace {

using slam2d::Pose2;

void requireSameSize(const std::vector<Pose2>& estimate, const std::vector<Pose2>& reference) {
  if (estimate.size() != reference.size()) {
    throw std::invalid_argument("trajectories differ in length: " + std::to_string(estimate.size()) + " estimated vs " +
                                std::to_string(reference.size()) + " reference poses");
  }
}

}  // namespace

ErrorStats errorStats(const std::vector<double>& errors) {
  ErrorStats s;
  s.count = errors.size();
  if (errors.empty()) {
    s.mean = s.std = s.rmse = s.max = std::numeric_limits<double>::quiet_NaN();
    return s;
  }
  double sum = 0.0, sum2 = 0.0;
  for (double e : errors) {
    sum += e;
    sum2 += e * e;
    s.max = std::max(s.max, e);
  }
  const double n = double(errors.size());
  s.mean = sum / n;
  s.rmse = std::sqrt(sum2 / n);
  double var = 0.0;
  for (double e : errors) var += (e - s.mean) * (e - s.mean);
  s.std = std::sqrt(var / n);
  return s;
}

RelationErrors relationErrors(const std::vector<StampedPose2>& trajectory,
                              const std::vector<datasets::SlamRelation>& relations) {
  std::unordered_map<int64_t, size_t> index;
  index.reserve(trajectory.size());
  for (size_t i = 0; i < trajectory.size(); ++i) index.emplace(trajectory[i].stamp_ns, i);
  std::vector<double> translation, rotation;
  for (const datasets::SlamRelation& r : relations) {
    const auto a = index.find(r.from_stamp_ns), b = index.find(r.to_stamp_ns);
    if (a == index.end() || b == index.end()) continue;
    const Pose2 estimated = slam2d::between(trajectory[a->second].pose, trajectory[b->second].pose);
    const Pose2 e = slam2d::between(r.motion, estimated);
    translation.push_back(e.translation().norm());
    rotation.push_back(std::abs(e.theta_rad));
  }
  return {translation.size(), errorStats(translation), errorStats(rotation)};
}

Pose2 alignRigid2d(const std::vector<Pose2>& estimate, const std::vector<Pose2>& reference) {
  requireSameSize(estimate, reference);
  if (estimate.empty()) return {};
  Eigen::Vector2d mean_est = Eigen::Vector2d::Zero(), mean_ref = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < estimate.size(); ++i) {
    mean_est += estimate[i].translation();
    mean_ref += reference[i].translation();
  }
  mean_est /= double(estimate.size());
  mean_ref /= double(estimate.size());
  // The rotation maximising Σ q_ref · R q_est has angle atan2(Σ q_est × q_ref, Σ q_est · q_ref).
  double dot = 0.0, cross = 0.0;
  for (size_t i = 0; i < estimate.size(); ++i) {
    const Eigen::Vector2d p = estimate[i].translation() - mean_est, q = reference[i].translation() - mean_ref;
    dot += p.dot(q);
    cross += p.x() * q.y() - p.y() * q.x();
  }
  const double theta = (dot == 0.0 && cross == 0.0) ? 0.0 : std::atan2(cross, dot);
  const Pose2 rotation{0.0, 0.0, theta};
  const Eigen::Vector2d t = mean_ref - rotation * mean_est;
  return {t.x(), t.y(), theta};
}

ErrorStats absoluteTrajectoryError(const std::vector<Pose2>& estimate, const std::vector<Pose2>& reference) {
  const Pose2 align = alignRigid2d(estimate, reference);
  std::vector<double> errors(estimate.size());
  for (size_t i = 0; i < estimate.size(); ++i) {
    errors[i] = (align * estimate[i].translation() - reference[i].translation()).norm();
  }
  return errorStats(errors);
}

RelativePoseErrors relativePoseError(const std::vector<Pose2>& estimate, const std::vector<Pose2>& reference,
                                     double distance_m) {
  requireSameSize(estimate, reference);
  if (!(distance_m > 0.0)) throw std::invalid_argument("RPE distance must be > 0 m");
  // path[i]: reference path length from pose 0 to pose i
  std::vector<double> path(reference.size(), 0.0);
  for (size_t i = 1; i < reference.size(); ++i) {
    path[i] = path[i - 1] + (reference[i].translation() - reference[i - 1].translation()).norm();
  }
  std::vector<double> translation, rotation;
  size_t j = 0;
  for (size_t i = 0; i < reference.size(); ++i) {
    j = std::max(j, i + 1);
    while (j < reference.size() && path[j] - path[i] < distance_m) ++j;
    if (j == reference.size()) break;
    const Pose2 e = slam2d::between(slam2d::between(reference[i], reference[j]), slam2d::between(estimate[i], estimate[j]));
    translation.push_back(e.translation().norm());
    rotation.push_back(std::abs(e.theta_rad));
  }
  return {errorStats(translation), errorStats(rotation)};
}

}  // namespace rmap::bench
