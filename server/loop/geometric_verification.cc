#include "loop/geometric_verification.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <random>
#include <stdexcept>
#include <string>

#include "loop/descriptor_matching.h"

namespace rmap::loop {

void GeometricVerificationOptions::validate() const {
  auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("GeometricVerificationOptions: ") + what);
  };
  require(max_distance_fraction > 0.0 && max_distance_fraction < 0.5, "max_distance_fraction must be in (0, 0.5)");
  require(ratio > 0.0 && ratio <= 1.0, "ratio must be in (0, 1]");
  require(ransac_threshold_px > 0.0, "ransac_threshold_px must be > 0");
  require(ransac_confidence > 0.0 && ransac_confidence < 1.0, "ransac_confidence must be in (0, 1)");
  require(ransac_iterations >= 1, "ransac_iterations must be >= 1");
  require(min_matches >= 8, "min_matches must be >= 8 (the 8-point fundamental matrix)");
  require(max_scale_error > 0.0 && max_scale_error < 1.0, "max_scale_error must be in (0, 1)");
  require(ransac_threshold_m > 0.0, "ransac_threshold_m must be > 0");
  require(ransac_threshold_rad >= 0.0, "ransac_threshold_rad must be >= 0");
}

namespace {

/// The putative matches (query row, reference row), after checking the inputs.
std::vector<std::pair<int, int>> putativeMatches(size_t query_points, const cv::Mat& query_descriptors,
                                                 size_t reference_points, const cv::Mat& reference_descriptors,
                                                 const GeometricVerificationOptions& options) {
  if (query_descriptors.type() != CV_8U || reference_descriptors.type() != CV_8U ||
      query_descriptors.cols != reference_descriptors.cols ||
      query_points != static_cast<size_t>(query_descriptors.rows) ||
      reference_points != static_cast<size_t>(reference_descriptors.rows)) {
    throw std::invalid_argument("geometric verification: descriptors must be CV_8U of one width, one row per point");
  }
  if (query_descriptors.rows < options.min_matches || reference_descriptors.rows < options.min_matches) return {};
  const int max_bits = static_cast<int>(options.max_distance_fraction * query_descriptors.cols * 8);
  return mutualMatches(query_descriptors, reference_descriptors, max_bits, options.ratio);
}

/// Rigid motion (no scale) taking the columns of `from` onto those of `to`, least squares.
Eigen::Isometry3d rigidFit(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to) {
  Eigen::Isometry3d t;
  t.matrix() = Eigen::umeyama(from, to, false);
  return t;
}

/// Rigid motion (no scale) taking the masked points of `from` onto those of `to`, least squares:
/// in 2D the angle is that of the summed cross and dot products of the centred pairs (Eigen's
/// umeyama does the same, but its fixed-size 2D code trips gcc 12's -Wstringop-overread).
Eigen::Isometry2d rigidFit2d(const std::vector<cv::Point2f>& from, const std::vector<cv::Point2f>& to,
                             const std::vector<uchar>& mask) {
  Eigen::Vector2d from_mean = Eigen::Vector2d::Zero(), to_mean = Eigen::Vector2d::Zero();
  double n = 0.0;
  for (size_t k = 0; k < from.size(); ++k) {
    if (!mask[k]) continue;
    from_mean += Eigen::Vector2d(from[k].x, from[k].y);
    to_mean += Eigen::Vector2d(to[k].x, to[k].y);
    ++n;
  }
  from_mean /= n;
  to_mean /= n;
  double dot = 0.0, cross = 0.0;
  for (size_t k = 0; k < from.size(); ++k) {
    if (!mask[k]) continue;
    const Eigen::Vector2d a = Eigen::Vector2d(from[k].x, from[k].y) - from_mean;
    const Eigen::Vector2d b = Eigen::Vector2d(to[k].x, to[k].y) - to_mean;
    dot += a.dot(b);
    cross += a.x() * b.y() - a.y() * b.x();
  }
  Eigen::Isometry2d fit = Eigen::Isometry2d::Identity();
  fit.linear() = Eigen::Rotation2Dd(std::atan2(cross, dot)).toRotationMatrix();
  fit.translation() = to_mean - fit.linear() * from_mean;
  return fit;
}

}  // namespace

Verification verifyGeometry(const std::vector<cv::Point2f>& query_points, const cv::Mat& query_descriptors,
                            const std::vector<cv::Point2f>& reference_points, const cv::Mat& reference_descriptors,
                            const GeometricVerificationOptions& options) {
  Verification v;
  std::vector<cv::Point2f> q, r;
  for (const auto& [i, j] : putativeMatches(query_points.size(), query_descriptors, reference_points.size(),
                                            reference_descriptors, options)) {
    q.push_back(query_points[i]);
    r.push_back(reference_points[j]);
  }
  v.matches = static_cast<int>(q.size());
  if (v.matches < options.min_matches) return v;
  std::vector<uchar> mask;
  if (options.model == GeometricModel::kRigid2d) {
    const cv::Mat m = cv::estimateAffinePartial2D(q, r, mask, cv::RANSAC, options.ransac_threshold_px,
                                                  static_cast<size_t>(options.ransac_iterations),
                                                  options.ransac_confidence);
    if (m.empty()) return v;
    // [s·cos, −s·sin, tx; s·sin, s·cos, ty]
    const double scale = std::hypot(m.at<double>(0, 0), m.at<double>(1, 0));
    if (std::abs(scale - 1.0) > options.max_scale_error) return v;
    // The motion without the scale: the pixels are metric, the same size at both visits.
    v.reference_from_query_px = rigidFit2d(q, r, mask);
  } else {
    const cv::Mat f = cv::findFundamentalMat(q, r, cv::FM_RANSAC, options.ransac_threshold_px,
                                             options.ransac_confidence, options.ransac_iterations, mask);
    if (f.empty()) return v;
  }
  for (uchar m : mask) v.inliers += m ? 1 : 0;
  return v;
}

Verification verifyRigid3d(const std::vector<Eigen::Vector3f>& query_points_m, const cv::Mat& query_descriptors,
                           const std::vector<Eigen::Vector3f>& reference_points_m,
                           const cv::Mat& reference_descriptors, const GeometricVerificationOptions& options) {
  Verification v;
  const std::vector<std::pair<int, int>> pairs = putativeMatches(
      query_points_m.size(), query_descriptors, reference_points_m.size(), reference_descriptors, options);
  v.matches = static_cast<int>(pairs.size());
  if (v.matches < options.min_matches) return v;
  const int n = v.matches;
  Eigen::Matrix3Xd q(3, n), r(3, n);
  Eigen::VectorXd tolerance_m(n);
  for (int k = 0; k < n; ++k) {
    q.col(k) = query_points_m[pairs[k].first].cast<double>();
    r.col(k) = reference_points_m[pairs[k].second].cast<double>();
    tolerance_m(k) = options.ransac_threshold_m + options.ransac_threshold_rad * r.col(k).norm();
  }
  const auto inliersOf = [&](const Eigen::Isometry3d& t, std::vector<int>* members) {
    int count = 0;
    for (int k = 0; k < n; ++k) {
      if ((t * q.col(k) - r.col(k)).norm() > tolerance_m(k)) continue;
      ++count;
      if (members) members->push_back(k);
    }
    return count;
  };
  // Fixed seed: the same two frames always give the same answer.
  std::mt19937 rng(0x5eed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  int best = 0;
  Eigen::Isometry3d best_fit = Eigen::Isometry3d::Identity();
  int iterations = options.ransac_iterations;
  for (int it = 0; it < iterations; ++it) {
    int s[3] = {pick(rng), pick(rng), pick(rng)};
    if (s[0] == s[1] || s[0] == s[2] || s[1] == s[2]) continue;
    // A rigid motion keeps distances: a sample whose sides differ cannot be one (most wrong samples end here).
    bool keeps_sides = true;
    for (int a = 0; a < 3 && keeps_sides; ++a) {
      const int i = s[a], j = s[(a + 1) % 3];
      const double side_q = (q.col(i) - q.col(j)).norm(), side_r = (r.col(i) - r.col(j)).norm();
      keeps_sides = std::abs(side_q - side_r) <= tolerance_m(i) + tolerance_m(j) && side_r > tolerance_m(i);
    }
    if (!keeps_sides) continue;
    // Three points on a line leave the turn about it free: the sample must span a triangle.
    const Eigen::Vector3d ab = r.col(s[1]) - r.col(s[0]), ac = r.col(s[2]) - r.col(s[0]), bc = ac - ab;
    const double longest_side = std::max({ab.norm(), ac.norm(), bc.norm()});
    if (ab.cross(ac).norm() / longest_side <= std::max({tolerance_m(s[0]), tolerance_m(s[1]), tolerance_m(s[2])})) {
      continue;
    }
    Eigen::Matrix3d from, to;
    for (int a = 0; a < 3; ++a) {
      from.col(a) = q.col(s[a]);
      to.col(a) = r.col(s[a]);
    }
    const Eigen::Isometry3d fit = rigidFit(from, to);
    const int count = inliersOf(fit, nullptr);
    if (count <= best) continue;
    best = count;
    best_fit = fit;
    // Enough iterations for `confidence` of drawing one all-inlier sample at this inlier ratio.
    const double all_inliers = std::pow(static_cast<double>(count) / n, 3);
    if (all_inliers >= 1.0) break;
    const double needed = std::log(1.0 - options.ransac_confidence) / std::log(1.0 - all_inliers);
    iterations = static_cast<int>(std::min<double>(iterations, std::ceil(needed)));  // in double: needed may pass INT_MAX
  }
  if (best < 3) return v;
  // Refined on the sample's inliers; kept when it holds at least as many.
  std::vector<int> members;
  inliersOf(best_fit, &members);
  Eigen::Matrix3Xd from(3, members.size()), to(3, members.size());
  for (size_t k = 0; k < members.size(); ++k) {
    from.col(k) = q.col(members[k]);
    to.col(k) = r.col(members[k]);
  }
  // Inliers along one line (a wall's edge, one ring on a far wall) measure no turn about that
  // line, whatever their number: the fit could be that line's mirror image (seen: 180° off).
  const Eigen::Matrix3Xd centred = to.colwise() - to.rowwise().mean();
  const Eigen::Vector3d spread = Eigen::JacobiSVD<Eigen::Matrix3Xd>(centred).singularValues();
  if (spread(1) / std::sqrt(static_cast<double>(members.size())) <= options.ransac_threshold_m) return v;
  const Eigen::Isometry3d refined = rigidFit(from, to);
  if (const int count = inliersOf(refined, nullptr); count >= best) {
    best = count;
    best_fit = refined;
  }
  v.inliers = best;
  v.reference_from_query = best_fit;
  return v;
}

}  // namespace rmap::loop
