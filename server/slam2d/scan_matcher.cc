#include "slam2d/scan_matcher.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <vector>

namespace rmap::slam2d {

namespace {

struct Normal {
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  double residual = 0.0;
};

/// Accumulates the normal equations of the data terms at pose ξ on one level.
Normal accumulate(const GridMap2d& map, int level, std::span<const MatchPoint> points, const Pose2& xi,
                  double reflectivity_weight) {
  const OccupancyGrid& grid = map.level(level);
  const double c = std::cos(xi.theta_rad), s = std::sin(xi.theta_rad);
  Normal n;
  Eigen::Matrix3d h_refl = Eigen::Matrix3d::Zero();
  Eigen::Vector3d g_refl = Eigen::Vector3d::Zero();
  const bool use_refl = level == 0 && reflectivity_weight > 0.0;
  for (const MatchPoint& pt : points) {
    const Eigen::Vector2d rotated(c * pt.p_m.x() - s * pt.p_m.y(), s * pt.p_m.x() + c * pt.p_m.y());
    const Eigen::Vector2d w(rotated.x() + xi.x_m, rotated.y() + xi.y_m);
    const OccupancyGrid::Sample m = grid.sample(w);
    const double r = 1.0 - m.value;
    n.residual += r;
    // ∂S/∂θ = (−rotated.y, rotated.x).
    const Eigen::Vector3d j(m.gradient_per_m.x(), m.gradient_per_m.y(),
                            -m.gradient_per_m.x() * rotated.y() + m.gradient_per_m.y() * rotated.x());
    n.h.noalias() += j * j.transpose();
    n.g.noalias() += j * r;
    if (use_refl && std::isfinite(pt.reflectivity)) {
      const ReflectivityLayer::Sample rs = map.reflectivityLayer().sample(w);
      if (rs.support < 0.25f) continue;  // no fused reflectivity near this endpoint
      const double e = pt.reflectivity - rs.value;
      const Eigen::Vector3d jr(rs.gradient_per_m.x(), rs.gradient_per_m.y(),
                               -rs.gradient_per_m.x() * rotated.y() + rs.gradient_per_m.y() * rotated.x());
      h_refl.noalias() += jr * jr.transpose();
      g_refl.noalias() += jr * e;
    }
  }
  const double inv_n = 1.0 / static_cast<double>(points.size());
  n.h = (n.h + reflectivity_weight * h_refl) * inv_n;
  n.g = (n.g + reflectivity_weight * g_refl) * inv_n;
  n.residual *= inv_n;
  return n;
}

/// The best of a small grid of poses around `initial` by Σ M on the coarsest
/// level, weighed by the distance to the guess (search_*_weight); another
/// pose must beat the guess by 2 % to replace it, so flat scores (corridor,
/// open space) keep the guess.
Pose2 correlativeSearch(const GridMap2d& map, std::span<const MatchPoint> points, const Pose2& initial,
                        const ScanMatcherOptions& options) {
  const OccupancyGrid& grid = map.level(map.levelCount() - 1);
  const size_t stride = std::max<size_t>(1, points.size() / static_cast<size_t>(std::max(1, options.search_points)));
  const int steps = static_cast<int>(std::floor(options.search_rad / options.search_step_rad));
  const double d = grid.resolution_m();
  const int reach = static_cast<int>(std::floor(options.search_m / d));
  std::vector<Eigen::Vector2d> shifts;
  for (int i = -reach; i <= reach; ++i)
    for (int j = -reach; j <= reach; ++j) shifts.emplace_back(i * d, j * d);
  auto score = [&](double theta, const Eigen::Vector2d& t) {
    const double c = std::cos(theta), s = std::sin(theta);
    double sum = 0.0;
    for (size_t i = 0; i < points.size(); i += stride) {
      const Eigen::Vector2d& p = points[i].p_m;
      sum += grid.sample({c * p.x() - s * p.y() + t.x(), s * p.x() + c * p.y() + t.y()}).value;
    }
    return sum;
  };
  Pose2 best = initial;
  double best_score = 1.02 * score(initial.theta_rad, initial.translation());
  for (int k = -steps; k <= steps; ++k) {
    const double theta = initial.theta_rad + k * options.search_step_rad;
    for (const Eigen::Vector2d& shift : shifts) {
      if (k == 0 && shift.isZero()) continue;
      const Eigen::Vector2d t = initial.translation() + shift;
      const double sc = score(theta, t) * std::exp(-options.search_rotation_weight * std::pow(k * options.search_step_rad, 2) -
                                                   options.search_translation_weight * shift.squaredNorm());
      if (sc > best_score) best_score = sc, best = {t.x(), t.y(), normalizeAngle(theta)};
    }
  }
  return best;
}

/// Adds to the normal equations the prior along the weaker translation
/// eigenvector of those equations so far: the data and the fixed prior (see
/// ScanMatcherOptions::flat_information_cells).
/// @param offset_m      pose translation minus the prior's (m)
/// @param resolution_m  cell edge of the level the equations are for
void addFlatDirectionPrior(Normal& n, const Eigen::Vector2d& offset_m, double resolution_m,
                           const ScanMatcherOptions& options) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(n.h.topLeftCorner<2, 2>());
  const double strong = eigen.eigenvalues()(1);
  if (!(strong > 0.0)) return;
  if (eigen.eigenvalues()(0) >= options.flat_ratio * strong) return;
  const Eigen::Vector2d flat = eigen.eigenvectors().col(0);
  const Eigen::Matrix2d information =
      options.flat_information_cells / (resolution_m * resolution_m) * flat * flat.transpose();
  n.h.topLeftCorner<2, 2>() += information;
  n.g.head<2>() -= information * offset_m;
}

}  // namespace

MatchResult matchScan(const GridMap2d& map, std::span<const MatchPoint> points, const Pose2& initial,
                      const std::optional<PosePrior>& prior, const ScanMatcherOptions& options) {
  MatchResult result;
  result.pose = initial;
  if (points.empty() || map.empty()) return result;
  Pose2 xi = options.search_rad > 0.0 && options.search_step_rad > 0.0
                 ? correlativeSearch(map, points, initial, options)
                 : initial;
  for (int level = map.levelCount() - 1; level >= 0; --level) {
    const int iterations = level == 0 ? options.fine_iterations : options.coarse_iterations;
    const double max_step_m = options.max_step_cells * map.level(level).resolution_m();
    for (int it = 0; it < iterations; ++it) {
      Normal n = accumulate(map, level, points, xi, options.reflectivity_weight);
      ++result.iterations;
      if (prior) {
        const Eigen::Vector3d e(xi.x_m - prior->pose.x_m, xi.y_m - prior->pose.y_m,
                                normalizeAngle(xi.theta_rad - prior->pose.theta_rad));
        n.h.diagonal() += prior->information;
        n.g -= prior->information.cwiseProduct(e);
        if (options.flat_information_cells > 0.0)
          addFlatDirectionPrior(n, e.head<2>(), map.level(level).resolution_m(), options);
      }
      // Levenberg damping: a floor under every direction, so a flat one
      // (corridor axis) gets a small step rather than an arbitrary one.
      const double trace = n.h.trace();
      if (!(trace > 1e-12) || !std::isfinite(trace)) break;
      n.h.diagonal().array() += options.damping * trace / 3.0;
      Eigen::Vector3d step = n.h.ldlt().solve(n.g);
      if (!step.allFinite()) break;
      const double t = step.head<2>().norm();
      if (t > max_step_m) step.head<2>() *= max_step_m / t;
      step.z() = std::clamp(step.z(), -options.max_step_rad, options.max_step_rad);
      xi = {xi.x_m + step.x(), xi.y_m + step.y(), normalizeAngle(xi.theta_rad + step.z())};
      if (step.head<2>().norm() < options.converged_m && std::abs(step.z()) < options.converged_rad) break;
    }
  }
  const Normal final_terms = accumulate(map, 0, points, xi, 0.0);
  result.hessian = final_terms.h;
  result.mean_residual = final_terms.residual;
  if (xi.isFinite()) result.pose = xi;
  return result;
}

}  // namespace rmap::slam2d
