#pragma once
/// @file geometric_verification.h
/// Checks that two images see the same rigid scene: putative matches of
/// their binary descriptors (mutual nearest neighbours passing a ratio
/// test), then a fundamental matrix fitted by RANSAC (OpenCV); the inliers
/// are the evidence. The fundamental matrix needs no calibration, so it
/// holds for any pinhole camera; a panorama patch is near-pinhole locally.

#include <opencv2/core.hpp>
#include <vector>

namespace rmap::loop {

struct GeometricVerificationOptions {
  double max_distance_fraction = 0.25;  ///< putative matches within this fraction of the descriptor bits
  double ratio = 0.8;                   ///< nearest / second-nearest distance must be below this
  double ransac_threshold_px = 2.0;     ///< point-to-epipolar-line distance of an inlier, pixels
  double ransac_confidence = 0.99;
  int ransac_iterations = 500;
  /// Fewer putative matches: 0 inliers, no fit. Below 15 OpenCV fits by
  /// LMedS instead of RANSAC, at the same cost (3 ms per candidate, most of
  /// a frame's verification time on wrong candidates), and on Lip6 such
  /// candidates never got more than 8 inliers: below any loop's evidence.
  int min_matches = 15;
  /// @throws std::invalid_argument naming the first bad field
  void validate() const;
};

struct Verification {
  int matches = 0;  ///< putative matches
  int inliers = 0;  ///< RANSAC inliers of the fundamental matrix (0 when too few matches)
};

/// @param query_points, reference_points  keypoint positions (pixels) of each descriptor row
/// @param query_descriptors, reference_descriptors  CV_8U, same width
Verification verifyGeometry(const std::vector<cv::Point2f>& query_points, const cv::Mat& query_descriptors,
                            const std::vector<cv::Point2f>& reference_points, const cv::Mat& reference_descriptors,
                            const GeometricVerificationOptions& options);

}  // namespace rmap::loop
