#pragma once
/// @file geometric_verification.h
/// Checks that two images see the same rigid scene: putative matches of
/// their binary descriptors (mutual nearest neighbours passing a ratio
/// test), then a model fitted by RANSAC (OpenCV); the inliers are the
/// evidence. Two models:
///  - a fundamental matrix (camera images, intensity panoramas): it needs no
///    calibration, so it holds for any pinhole camera; a panorama patch is
///    near-pinhole locally;
///  - a 2D rigid motion (metric top-down images such as reflectivity
///    patches: the same place seen again is the same picture turned and
///    shifted, at the same scale): a rotation, a shift and a scale fitted by
///    RANSAC, and no inlier unless the scale is 1 within max_scale_error. Its
///    2 degrees of freedom fewer than the fundamental matrix's 7 leave
///    look-alike structure at another scale or with another layout nothing
///    to fit.

#include <opencv2/core.hpp>
#include <vector>

namespace rmap::loop {

enum class GeometricModel { kFundamental, kRigid2d };

struct GeometricVerificationOptions {
  GeometricModel model = GeometricModel::kFundamental;
  double max_scale_error = 0.1;         ///< kRigid2d: |scale − 1| of an accepted fit, in (0, 1)
  double max_distance_fraction = 0.25;  ///< putative matches within this fraction of the descriptor bits
  double ratio = 0.8;                   ///< nearest / second-nearest distance must be below this
  double ransac_threshold_px = 2.0;     ///< inlier distance (pixels): to the epipolar line, or of the moved point (kRigid2d)
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
  int inliers = 0;  ///< RANSAC inliers of the model (0 when too few matches, or a rigid fit's scale is off)
};

/// @param query_points, reference_points  keypoint positions (pixels) of each descriptor row
/// @param query_descriptors, reference_descriptors  CV_8U, same width
Verification verifyGeometry(const std::vector<cv::Point2f>& query_points, const cv::Mat& query_descriptors,
                            const std::vector<cv::Point2f>& reference_points, const cv::Mat& reference_descriptors,
                            const GeometricVerificationOptions& options);

}  // namespace rmap::loop
