#pragma once
/// @file geometric_verification.h
/// Checks that two images see the same rigid scene: putative matches of
/// their binary descriptors (mutual nearest neighbours passing a ratio
/// test), then a model fitted by RANSAC (OpenCV); the inliers are the
/// evidence. Three models:
///  - a fundamental matrix (camera images, intensity panoramas): it needs no
///    calibration, so it holds for any pinhole camera; a panorama patch is
///    near-pinhole locally;
///  - a 2D rigid motion (metric top-down images such as reflectivity
///    patches: the same place seen again is the same picture turned and
///    shifted, at the same scale): a rotation, a shift and a scale fitted by
///    RANSAC, and no inlier unless the scale is 1 within max_scale_error (the
///    motion, refitted without scale, measures the revisit's offset). Its
///    2 degrees of freedom fewer than the fundamental matrix's 7 leave
///    look-alike structure at another scale or with another layout nothing
///    to fit;
///  - a 3D rigid motion (images whose pixels carry the 3D point they show in
///    the sensor frame, such as lidar intensity panoramas): keypoints lifted
///    to metres, a rotation and a shift fitted by RANSAC on 3 matches
///    (Umeyama, Eigen). Six degrees of freedom in metres: a look-alike place
///    elsewhere (another storey, a repeated corridor) must also repeat its
///    3D layout around the sensor, which a fundamental matrix never asks.
///    Samples and inlier sets along one line are refused: they leave the turn
///    about that line free (a fit can come out 180° off).

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

namespace rmap::loop {

enum class GeometricModel { kFundamental, kRigid2d, kRigid3d };

struct GeometricVerificationOptions {
  GeometricModel model = GeometricModel::kFundamental;
  double max_scale_error = 0.1;         ///< kRigid2d: |scale − 1| of an accepted fit, in (0, 1)
  double max_distance_fraction = 0.25;  ///< putative matches within this fraction of the descriptor bits
  double ratio = 0.8;                   ///< nearest / second-nearest distance must be below this
  double ransac_threshold_px = 2.0;     ///< inlier distance (pixels): to the epipolar line, or of the moved point (kRigid2d)
  /// kRigid3d: a moved query point is an inlier within ransac_threshold_m + ransac_threshold_rad × its
  /// reference point's range (a keypoint lifted to the point of a pixel a few pixels away lands that
  /// far off, farther the farther it is).
  double ransac_threshold_m = 0.2;      ///< metres, > 0
  double ransac_threshold_rad = 0.03;   ///< rad, ≥ 0
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
  /// verifyRigid3d with inliers: the fitted motion, reference sensor frame from query sensor frame.
  Eigen::Isometry3d reference_from_query = Eigen::Isometry3d::Identity();
  /// kRigid2d with inliers: the rigid motion (scale 1, refitted on the inliers) taking query
  /// pixels onto reference pixels (x = column, y = row).
  std::optional<Eigen::Isometry2d> reference_from_query_px;
};

/// @param query_points, reference_points  keypoint positions (pixels) of each descriptor row
/// @param query_descriptors, reference_descriptors  CV_8U, same width
Verification verifyGeometry(const std::vector<cv::Point2f>& query_points, const cv::Mat& query_descriptors,
                            const std::vector<cv::Point2f>& reference_points, const cv::Mat& reference_descriptors,
                            const GeometricVerificationOptions& options);

/// The kRigid3d model (whatever options.model says): keypoints as 3D points.
/// @param query_points_m, reference_points_m  each descriptor row's point, metres, in its sensor frame (finite)
/// @throws std::invalid_argument for descriptors not CV_8U of one width, or not one row per point
Verification verifyRigid3d(const std::vector<Eigen::Vector3f>& query_points_m, const cv::Mat& query_descriptors,
                           const std::vector<Eigen::Vector3f>& reference_points_m,
                           const cv::Mat& reference_descriptors, const GeometricVerificationOptions& options);

}  // namespace rmap::loop
