#pragma once
/// @file calibration_eval.h
/// How well intensity calibration turns raw laser intensity into a
/// reflectivity that does not depend on the viewpoint, measured where the
/// truth is known (the simulator) and checked on real lidar intensities.
///
/// Simulation, per scanner preset (sim::Laser2dModel sickLike, hokuyoLike):
/// two procedural buildings with a robot tour each (known poses). The
/// supervised calibration is fitted on the first building with the true
/// reflectivity of every return as targets and scored on the second; the
/// self-calibration is fitted on the second building's returns grouped by
/// map cell, its scale set by one reference surface of known reflectivity
/// (the surface of the building seen most, as a surveyed wall would be), and
/// scored there. Incidence is
/// always the one estimated from the scan (slam2d::cosIncidence), as on a robot.
///
/// Figures: reflectivity_rel_err_median is the median over the scored returns
/// of |ρ̂ − ρ| / ρ; coverage the fraction of returns that got a reflectivity
/// (the rest: saturated, outside the learned support, no normal); spread is
/// the median over cells with at least min_views returns of the coefficient
/// of variation (std / mean) of a cell's values over its returns, raw
/// intensity vs calibrated reflectivity, on the same returns.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "slam2d/incidence.h"
#include "slam2d/self_calibration.h"

namespace rmap::bench {

struct CalibrationEvalOptions {
  int poses = 300;                ///< scans per simulated run
  uint64_t seed = 1;              ///< building and tour of the calibration run; the test run uses seed + 1
  double sensor_height_m = 0.5;   ///< laser above the floor, metres
  double cell_m = 0.05;           ///< map cell edge for self-calibration and spread, metres
  int min_views = 10;             ///< cells with fewer returns scored by both calibrations are left out of the spread
  slam2d::IncidenceOptions incidence;
  slam2d::CalibrationFitOptions supervised;
  slam2d::SelfCalibrationOptions self;
  /// Folder with source.ply and target.ply (and T_target_source.txt) for the real check; empty: skipped.
  std::string lidar_pair_dir;
  std::string json_out;           ///< write the results here when not empty
};

struct CalibrationScore {
  double rel_err_median = 0.0;  ///< |ρ̂ − ρ| / ρ, median over returns with a reflectivity
  double rel_err_p90 = 0.0;     ///< its 90th percentile
  double coverage = 0.0;        ///< fraction of returns with a reflectivity
  double spread = 0.0;          ///< median coefficient of variation per cell (see file comment)
};

struct ScannerCalibrationEval {
  std::string scanner;
  size_t scans = 0;                       ///< per run
  size_t returns = 0;                     ///< returns of the test run
  double incidence_err_deg_median = 0.0;  ///< |α̂ − α| over returns with an estimate
  double incidence_coverage = 0.0;        ///< fraction of returns with an estimate
  double saturation_true = 0.0;           ///< the preset's clipping level, counts
  double saturation_detected = 0.0;       ///< level the supervised fit flagged, counts (+inf: none)
  CalibrationScore supervised;
  CalibrationScore self;
  /// Diagnostics: the supervised fit with the true incidence (the model's own
  /// floor, without the incidence estimator), and the self-calibration's
  /// error after the best global scale (its shape, without the reference).
  double supervised_true_incidence_rel_err_median = 0.0;
  double self_shape_rel_err_median = 0.0;
  size_t reference_views = 0;             ///< returns of the self-calibration's reference surface
  double reference_reflectivity = 0.0;
  double spread_raw = 0.0;                ///< median coefficient of variation of raw intensity per cell
  size_t spread_cells = 0;
  std::string supervised_calibration;     ///< the fitted files (IntensityCalibration::toText)
  std::string self_calibration;
};

/// Runs the simulation part for both presets.
/// @throws std::invalid_argument for bad options
std::vector<ScannerCalibrationEval> evaluateSimulatedCalibration(const CalibrationEvalOptions& options);

/// Real lidar pair (3D, 32 beams): range and incidence (from a local plane
/// fit) per point, self-calibration on voxels seen by both scans (fitted on
/// half the voxels, scored on the other half).
struct LidarIntensityCheck {
  size_t points[2] = {0, 0};          ///< returns per scan (points at the origin are no-returns)
  size_t planar_points[2] = {0, 0};   ///< with an incidence estimate
  double spearman_range = 0.0;        ///< rank correlation of intensity with range over planar points
  double spearman_cos = 0.0;          ///< rank correlation of intensity with cos α
  double response_range_ratio = 0.0;  ///< fitted g at the 10th / 90th range percentile, normal incidence
  double response_incidence_ratio = 0.0;  ///< fitted g at 60° / at 0°, median range
  size_t shared_cells = 0;            ///< held-out voxels with points from both scans
  double between_scans_raw = 0.0;     ///< median |m₁ − m₂| / ((m₁ + m₂)/2) of a voxel's mean per scan, raw
  double between_scans_calibrated = 0.0;
  double within_cell_raw = 0.0;       ///< median coefficient of variation over a voxel's points, raw
  double within_cell_calibrated = 0.0;
  double coverage = 0.0;              ///< held-out planar points with a reflectivity
};

/// @throws std::runtime_error when the files cannot be read
LidarIntensityCheck evaluateLidarPair(const std::string& dir, const CalibrationEvalOptions& options);

nlohmann::json toJson(const ScannerCalibrationEval& e);
nlohmann::json toJson(const LidarIntensityCheck& c);

/// rmap-bench calib: runs both parts, prints them, writes options.json_out.
/// @return process exit code
int runCalibrationBench(const CalibrationEvalOptions& options);

}  // namespace rmap::bench
