#pragma once
/// @file panorama.h
/// Panoramic 8-bit images of laser intensities (or reflectivities) of a 3D
/// cloud, for place recognition with image features (laser intensity works
/// where cameras see nothing).
///
/// Sensor frame: x forward, y left, z up. Azimuth a = atan2(y, x), elevation
/// e = atan2(z, √(x² + y²)). Column u = ⌊(π − a) / 2π · width⌋ mod width:
/// straight behind is column 0, forward the middle column, left of forward is
/// left in the image (as a viewer standing at the sensor sees it). Each pixel
/// keeps its closest point (a range image's z-buffer).
///
/// Projections:
///  - kEquirectangular: row v = ⌊(fov_up − e) / (fov_up − fov_down) · height⌋;
///    points outside [fov_down, fov_up] are dropped. Rows between two rings are
///    holes (filled, see below).
///  - kRingByColumn: one band of rows per laser ring, the top ring first; a
///    ring gets rows [i·height/R, (i+1)·height/R) (R rings), so the image does
///    not depend on the spacing of the rings. Rings are the given elevations or
///    found by clustering the cloud's elevations (estimateRingElevations).
///
/// Intensity → grey: linear from the low_percentile to the high_percentile of
/// the kept pixels' intensities onto 1..255 (clamped), so a few saturated or
/// dark returns do not wash the image out; 0 means no return. Holes are filled
/// with the mean of their non-empty 8-neighbours, fill_iterations times.
///
/// Cost: O(points + pixels · fill_iterations), plus O(points log points) when
/// ring elevations are estimated per cloud.

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <span>
#include <vector>

namespace rmap::loop {

enum class PanoramaProjection { kEquirectangular, kRingByColumn };

struct PanoramaOptions {
  PanoramaProjection projection = PanoramaProjection::kEquirectangular;
  int width_px = 1024;           ///< columns over 360°, [32, 16384]
  int height_px = 128;           ///< rows, [32, 4096]
  double fov_up_rad = 0.3927;    ///< kEquirectangular: elevation of the top edge (22.5°), rad, ≤ π/2
  double fov_down_rad = -0.3927; ///< kEquirectangular: elevation of the bottom edge, rad, ≥ −π/2, < fov_up_rad
  /// kRingByColumn: ring elevations (rad, any order). Empty: estimated from each
  /// cloud with ring_count (see estimateRingElevations).
  std::vector<float> ring_elevations_rad;
  int ring_count = 0;            ///< kRingByColumn, when estimating: rings expected; 0 = split at ring_gap_rad
  double ring_gap_rad = 0.0044;  ///< kRingByColumn, ring_count 0: elevation gap (0.25°) that separates rings, > 0
  double min_range_m = 0.1;      ///< closer points (and the (0,0,0) no-returns) are dropped, metres, ≥ 0
  double low_percentile = 0.01;  ///< [0, 1)
  double high_percentile = 0.99; ///< (low_percentile, 1]
  int fill_iterations = 4;       ///< hole-filling passes, [0, 64]

  /// @throws std::invalid_argument naming the first bad parameter
  void validate() const;
};

/// Projects points (sensor frame, metres) with intensities (any non-negative
/// unit: counts, reflectivity) into an 8-bit single-channel panorama of
/// height_px × width_px. Non-finite points or intensities are dropped.
/// @throws std::invalid_argument on bad options or a size mismatch
cv::Mat projectPanorama(std::span<const Eigen::Vector3f> points_sensor, std::span<const float> intensities,
                        const PanoramaOptions& options);

/// Same, and the index (into points_sensor) of the point each pixel shows in
/// `point_index` (CV_32SC1, same size; −1 for pixels without a point of their
/// own, hole-filled or empty), to lift image features back to 3D.
cv::Mat projectPanorama(std::span<const Eigen::Vector3f> points_sensor, std::span<const float> intensities,
                        const PanoramaOptions& options, cv::Mat& point_index);

/// The point image (point_image.h) of a panorama: each pixel's point from
/// `point_index` (as projectPanorama gave it), NaN for −1.
/// @throws std::invalid_argument unless point_index is CV_32SC1 with indices into points_sensor or −1
cv::Mat panoramaPoints(const cv::Mat& point_index, std::span<const Eigen::Vector3f> points_sensor);

/// Elevations (rad, ascending) of the laser rings of a cloud (sensor frame):
/// the sorted elevations split at the ring_count − 1 widest gaps, or, with
/// ring_count 0, at every gap wider than gap_rad; each ring is the median of its
/// points. Points at the origin or not finite are ignored.
/// @throws std::invalid_argument for ring_count < 0, gap_rad ≤ 0, or fewer
///         valid points than ring_count (or none)
std::vector<float> estimateRingElevations(std::span<const Eigen::Vector3f> points_sensor, int ring_count,
                                          double gap_rad = 0.0044);

}  // namespace rmap::loop
