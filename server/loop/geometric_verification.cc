#include "loop/geometric_verification.h"

#include <cmath>
#include <opencv2/calib3d.hpp>
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
}


Verification verifyGeometry(const std::vector<cv::Point2f>& query_points, const cv::Mat& query_descriptors,
                            const std::vector<cv::Point2f>& reference_points, const cv::Mat& reference_descriptors,
                            const GeometricVerificationOptions& options) {
  if (query_descriptors.type() != CV_8U || reference_descriptors.type() != CV_8U ||
      query_descriptors.cols != reference_descriptors.cols ||
      static_cast<int>(query_points.size()) != query_descriptors.rows ||
      static_cast<int>(reference_points.size()) != reference_descriptors.rows) {
    throw std::invalid_argument("verifyGeometry: descriptors must be CV_8U of one width, one row per point");
  }
  Verification v;
  if (query_descriptors.rows < options.min_matches || reference_descriptors.rows < options.min_matches) return v;
  const int max_bits = static_cast<int>(options.max_distance_fraction * query_descriptors.cols * 8);
  std::vector<cv::Point2f> q, r;
  for (const auto& [i, j] : mutualMatches(query_descriptors, reference_descriptors, max_bits, options.ratio)) {
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
  } else {
    const cv::Mat f = cv::findFundamentalMat(q, r, cv::FM_RANSAC, options.ransac_threshold_px,
                                             options.ransac_confidence, options.ransac_iterations, mask);
    if (f.empty()) return v;
  }
  for (uchar m : mask) v.inliers += m ? 1 : 0;
  return v;
}

}  // namespace rmap::loop
