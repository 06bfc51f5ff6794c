#pragma once
/// @file reflectivity_metrics.h
/// How well a simulated run's reflectivity map matches the truth and how
/// much the calibration removes the viewpoint from the readings.

#include <cstddef>
#include <vector>

#include "slam2d/pose2.h"
#include "slam2d/slam2d.h"
#include "slam2d/slam2d_dataset.h"

namespace rmap::bench {

/// NaN where a figure cannot be formed (no calibration, no cell seen enough).
struct ReflectivityFigures {
  /// Median over map cells with fused reflectivity of |s·ρ_map − ρ_true| / ρ_true,
  /// ρ_true the median true reflectivity of the returns landing in the cell.
  /// Self-calibration cannot observe the global scale, so s is the one
  /// factor that best fits (median of ρ_true / ρ_map over the cells).
  double rel_err_median = 0.0;
  double rel_err_median_unscaled = 0.0;  ///< the same with s = 1: the map as it is
  double scale = 0.0;                    ///< s
  size_t cells_compared = 0;
  /// Median over cells seen ≥ 5 times (with ≥ 5 calibrated readings when a
  /// calibration exists) of the coefficient of variation (std / mean) of the
  /// raw intensities of the returns landing in the cell, and of their
  /// calibrated reflectivities: how much a surface's reading changes with
  /// the viewpoint, before and after calibration.
  double spread_raw = 0.0;
  double spread_calibrated = 0.0;
  size_t cells_spread = 0;
};

/// Returns are placed with `laser_poses` (the SLAM's, so cells are the
/// map's) and calibrated with `slam`'s calibration of each scan's model.
/// @throws std::invalid_argument when laser_poses and the dataset's scans differ in number
ReflectivityFigures reflectivityFigures(const Slam2dDataset& data, const std::vector<slam2d::Pose2>& laser_poses,
                                        const slam2d::Slam2d& slam);

}  // namespace rmap::bench
