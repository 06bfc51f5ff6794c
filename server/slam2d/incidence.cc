#include "slam2d/incidence.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>

namespace rmap::slam2d {
namespace {

struct LineFit {
  Eigen::Vector2d normal;  ///< unit
  double rms_m;            ///< root mean square distance of the points to the line
  double max_m;            ///< largest distance of a point to the line
};

/// Total-least-squares line through points[first..last] (inclusive).
LineFit fitLine(const std::vector<Eigen::Vector2d>& points, int first, int last) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (int k = first; k <= last; ++k) mean += points[k];
  const double n = last - first + 1;
  mean /= n;
  double sxx = 0, sxy = 0, syy = 0;
  for (int k = first; k <= last; ++k) {
    const Eigen::Vector2d d = points[k] - mean;
    sxx += d.x() * d.x();
    sxy += d.x() * d.y();
    syy += d.y() * d.y();
  }
  sxx /= n, sxy /= n, syy /= n;
  // Smallest eigenvalue of [[sxx, sxy], [sxy, syy]] and its eigenvector.
  const double half_trace = 0.5 * (sxx + syy);
  const double root = std::hypot(0.5 * (sxx - syy), sxy);
  const double lambda_min = std::max(0.0, half_trace - root);
  // (A − λ_max I) has the minor eigenvector as its rows' direction; pick the better-conditioned row.
  const double lambda_max = half_trace + root;
  Eigen::Vector2d a(sxx - lambda_max, sxy), b(sxy, syy - lambda_max);
  Eigen::Vector2d normal = a.squaredNorm() > b.squaredNorm() ? a : b;
  if (normal.squaredNorm() == 0.0) normal = Eigen::Vector2d(1.0, 0.0);  // all points equal in one axis
  normal.normalize();
  double max_m = 0.0;
  for (int k = first; k <= last; ++k) max_m = std::max(max_m, std::abs(normal.dot(points[k] - mean)));
  return {normal, std::sqrt(lambda_min), max_m};
}

bool isReturn(float range_m, const LaserScan& scan) {
  return std::isfinite(range_m) && range_m > 0.0f && range_m >= scan.range_min_m &&
         (scan.range_max_m <= 0.0f || range_m <= scan.range_max_m);
}

void validate(const LaserScan& scan, const IncidenceOptions& o) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("cosIncidence: " + what); };
  if (scan.angles_rad.size() != scan.ranges_m.size()) {
    fail("angles_rad has " + std::to_string(scan.angles_rad.size()) + " entries, ranges_m " +
         std::to_string(scan.ranges_m.size()));
  }
  o.validate();
}

}  // namespace

void IncidenceOptions::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("IncidenceOptions: " + what); };
  if (!(window_m > 0.0) || !std::isfinite(window_m)) fail("window_m must be > 0");
  if (max_neighbours < 1) fail("max_neighbours must be ≥ 1");
  if (!(max_incidence_deg > 0.0 && max_incidence_deg < 90.0)) fail("max_incidence_deg must be in (0, 90)");
  if (!(range_sigma_m > 0.0) || !std::isfinite(range_sigma_m)) fail("range_sigma_m must be > 0");
}

std::vector<float> cosIncidence(const LaserScan& scan, const IncidenceOptions& options) {
  validate(scan, options);
  const size_t beams = scan.ranges_m.size();
  std::vector<float> cos_incidence(beams, std::numeric_limits<float>::quiet_NaN());

  // Returns in beam order: sensor-frame points, their beam, their surface.
  std::vector<Eigen::Vector2d> points;
  std::vector<size_t> beam_of;
  std::vector<int> surface;
  const double lambda_rad = (90.0 - options.max_incidence_deg) * std::numbers::pi / 180.0;
  const double sigma3 = 3.0 * options.range_sigma_m;
  for (size_t i = 0; i < beams; ++i) {
    const float r = scan.ranges_m[i];
    const double phi = scan.angles_rad[i];
    if (!isReturn(r, scan) || !std::isfinite(phi)) continue;
    const Eigen::Vector2d p(r * std::cos(phi), r * std::sin(phi));
    int id = 0;
    if (!points.empty()) {
      const double dphi = std::abs(phi - scan.angles_rad[beam_of.back()]);
      const double r_prev = points.back().norm();
      const bool joined = dphi < lambda_rad &&
                          (p - points.back()).norm() <= r_prev * std::sin(dphi) / std::sin(lambda_rad - dphi) + sigma3;
      id = joined ? surface.back() : surface.back() + 1;
    }
    points.push_back(p);
    beam_of.push_back(i);
    surface.push_back(id);
  }
  if (points.size() < 3) return cos_incidence;

  const double spacing_rad =
      std::abs(double(scan.angles_rad[beam_of.back()]) - scan.angles_rad[beam_of.front()]) / (points.size() - 1);
  const double flat_m = 3.0 * options.range_sigma_m;  // no point farther from the line than the range noise allows
  const int count = static_cast<int>(points.size());
  for (int k = 0; k < count; ++k) {
    const double range = points[k].norm();
    const double window = std::max(options.window_m, 2.5 * range * spacing_rad);
    int first = k, last = k;
    while (first > 0 && k - first < options.max_neighbours && surface[first - 1] == surface[k] &&
           (points[first - 1] - points[k]).norm() <= window) {
      --first;
    }
    while (last + 1 < count && last - k < options.max_neighbours && surface[last + 1] == surface[k] &&
           (points[last + 1] - points[k]).norm() <= window) {
      ++last;
    }
    std::optional<LineFit> best;
    auto consider = [&](int a, int b) {
      if (b - a < 2) return;
      const LineFit fit = fitLine(points, a, b);
      if (fit.max_m <= flat_m && (!best || fit.rms_m < best->rms_m)) best = fit;
    };
    consider(first, last);
    if (!best) {  // a corner inside the window: one side may still be a line
      consider(first, k);
      consider(k, last);
    }
    if (!best) continue;
    const double c = std::abs(best->normal.dot(points[k] / range));
    cos_incidence[beam_of[k]] = static_cast<float>(std::min(1.0, c));
  }
  return cos_incidence;
}

}  // namespace rmap::slam2d
