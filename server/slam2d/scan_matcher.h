#pragma once
/// @file scan_matcher.h
/// Hector scan-to-map matching (Kohlbrecher et al., SSRR 2011): Gauss–Newton
/// on Σ (1 − M(S_i(ξ)))² over the beam endpoints S_i, coarse to fine over the
/// occupancy pyramid, with
///  - an optional pose prior (the odometry prediction) as a weighted residual;
///  - an optional reflectivity residual on the finest level, Σ w (ρ_i − R(S_i(ξ)))²,
///    which constrains directions the geometry leaves free (a corridor with
///    differently reflective stretches);
///  - Levenberg damping and a step bound, so a degenerate Hessian (corridor,
///    open space) leaves the unconstrained directions at the initial guess
///    instead of sending them anywhere; a non-finite step is rejected.

#include <Eigen/Core>
#include <optional>
#include <span>

#include "slam2d/grid_map.h"
#include "slam2d/pose2.h"

namespace rmap::slam2d {

struct ScanMatcherOptions {
  int coarse_iterations = 3;          ///< Gauss–Newton iterations on each coarser level
  int fine_iterations = 5;            ///< ... and on the finest level
  double damping = 1e-2;              ///< Levenberg term, relative to the Hessian's trace
  double max_step_cells = 1.5;        ///< translation bound of one step, in cells of the level
  double max_step_rad = 0.15;         ///< rotation bound of one step (rad)
  /// With a prior only: more prior along the translation direction the data
  /// leaves nearly flat. Along such a direction (a corridor's axis, a lone
  /// wall) a few endpoints past the map's newest edge, where the map falls
  /// off to unknown, pull the pose back 3–4 cm a scan on the coarse levels,
  /// and nothing else holds it: a simulated wall seen to 5 m left the
  /// estimate 2.7–3 m behind. Where the weaker eigenvalue of a level's
  /// translation Hessian is below flat_ratio of the stronger, the prior gains
  /// flat_information_cells / d² along its eigenvector, d the level's cell
  /// edge (the data's curvature grows as 1/d²): 10/m² at 0.2 m, 160/m² at
  /// 0.05 m. On the coarse levels alone the wall was left 0.37–0.53 m behind;
  /// on every level 0.13–0.23 m. (The ratio is mostly 0.15–0.9 in the
  /// simulated building, 0.02–0.1 along that wall; 0.25 or more through a
  /// 25 cm slip.) Directions the data constrains move as before, so a slip
  /// the odometry missed is still caught; a fixed floor on x and y was not
  /// (docs/BENCHMARKS.md §4, *The coarse levels' pull along a flat
  /// direction* and *The flat-direction prior on every level*).
  double flat_information_cells = 0.4;  ///< 1/cell², ≥ 0 (0: off)
  double flat_ratio = 0.1;              ///< in [0, 1]
  double converged_m = 1e-4;          ///< stop a level when a step is below this translation (m) ...
  double converged_rad = 1e-4;        ///< ... and this rotation (rad)
  double reflectivity_weight = 0.0;   ///< per-point weight of the reflectivity residual (0 = off)
  /// Correlative search before Gauss–Newton, for a poor initial guess (no
  /// odometry): headings within ±search_rad of the guess in steps of
  /// search_step_rad, times translations within ±search_m in steps of the
  /// coarsest cell, scored by Σ M on the coarsest level over at most
  /// search_points points. search_rad = 0: off.
  double search_rad = 0.0;
  double search_m = 0.0;
  double search_step_rad = 0.025;
  int search_points = 60;
  /// The search's preference for poses near the guess: a candidate's Σ M is
  /// weighed by exp(−search_rotation_weight·Δθ² − search_translation_weight·|Δt|²),
  /// Δθ (rad) and Δt (m) its offset from the guess; 0: only the 2 % margin
  /// the guess keeps.
  double search_rotation_weight = 0.0;     ///< 1/rad²
  double search_translation_weight = 0.0;  ///< 1/m²
};

/// One endpoint in the robot base frame (m), with its calibrated reflectivity (NaN = none).
struct MatchPoint {
  Eigen::Vector2d p_m;
  float reflectivity = std::numeric_limits<float>::quiet_NaN();
};

/// Pose prior: residual diag(information)·(ξ − pose), in the units of the
/// mean per-point data term (so it does not depend on the beam count).
struct PosePrior {
  Pose2 pose;
  Eigen::Vector3d information = Eigen::Vector3d::Zero();  ///< 1/m², 1/m², 1/rad²
};

struct MatchResult {
  Pose2 pose;
  /// Mean per-point Gauss–Newton Hessian of the occupancy term at the finest
  /// level, x y θ: its small eigenvalues flag degenerate geometry.
  Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
  /// Mean of 1 − M over the points at the result (0 = every endpoint on a sure wall).
  double mean_residual = 1.0;
  int iterations = 0;
};

/// Matches a scan against the map from `initial` (robot base pose, map frame).
/// Always returns a finite pose: `initial` (or the prior) when nothing constrains it.
MatchResult matchScan(const GridMap2d& map, std::span<const MatchPoint> points, const Pose2& initial,
                      const std::optional<PosePrior>& prior, const ScanMatcherOptions& options);

}  // namespace rmap::slam2d
