#pragma once
/// @file self_calibration.h
/// Learning an IntensityCalibration from data: from calibration targets of
/// known reflectivity (fitCalibration), or from the map alone, where the same
/// cell is seen from many ranges and angles (selfCalibrate).
///
/// Both fits solve the same problem in log space, where it is linear:
///   ln Iⱼ = ln ρ_c(j) + R(ln rⱼ) + A(αⱼ) + εⱼ,
/// with ρ known per reading (targets) or one unknown per cell (self). The
/// cell terms are eliminated exactly (Schur complement of the block-diagonal
/// cell part, the closed form of alternating between cell reflectivities and
/// the response), the splines carry a second-difference penalty (P-splines)
/// that only matters where data is sparse, and iteratively reweighted least
/// squares (Cauchy weights on MAD-scaled residuals) discounts cells that mix
/// two materials and misregistered beams. Saturated readings are left out:
/// above a given level, or above a pile-up of readings at the top of the count
/// range (detectSaturation) that the fit confirms — the readings in the pile
/// must fall short of what their cell and g predict, as clipped readings do.
///
/// Self-calibration cannot observe the global scale (ρ·g is all it sees). It
/// is fixed by normalisation: the median cell reflectivity becomes
/// SelfCalibrationOptions::median_reflectivity. Absolute reflectivity then
/// needs one reference: IntensityCalibration::anchoredTo(readings of a target
/// of known ρ), or a calibration file of the same scanner model fitted on
/// targets (fitCalibration) used instead.

#include <cstdint>
#include <limits>
#include <vector>

#include "slam2d/intensity_calibration.h"

namespace rmap::slam2d {

struct CalibrationFitOptions {
  /// Knot spacing of R over ln r (0.15: knots 16 % apart in range).
  double range_knot_step = 0.15;
  /// Knot spacing of A over incidence, degrees.
  double incidence_knot_step_deg = 10.0;
  /// Readings seen more obliquely are left out; the support ends at the
  /// most oblique reading used. Degrees, (0, 90).
  double max_incidence_deg = 75.0;
  /// Weight of the second-difference penalty relative to the mean weight of
  /// data per coefficient, ≥ 0.
  double smoothness = 0.01;
  /// Counts at and above which readings are saturated; NaN: detectSaturation, confirmed by the fit.
  double saturation = std::numeric_limits<double>::quiet_NaN();
  /// Reweighting rounds after the least-squares start, ≥ 0.
  int robust_iterations = 5;
  /// Fewest usable readings a fit accepts, ≥ 1.
  size_t min_readings = 100;
  /// g below this fraction of its largest value in the support gives no reflectivity, [0, 1).
  double min_response_fraction = 1e-3;
};

/// Saturation level of a scanner from its readings: the saturated ones pile
/// up in a narrow peak (receiver noise, at most ±15 %) at the top of the
/// count range, twice as dense as the readings just below it. Readings at or
/// above the returned level (the peak's lower 3σ edge) are saturated. A
/// crowd of bright unclipped readings can look the same; the fits therefore
/// keep the level only when the readings above it fall short of g.
/// @return counts, or +inf when there is no such peak
double detectSaturation(const std::vector<float>& intensities);

/// Supervised fit on calibration targets of known reflectivity.
/// @throws std::invalid_argument for bad options or fewer than min_readings usable readings
IntensityCalibration fitCalibration(const std::vector<ReflectivityObservation>& observations,
                                    const CalibrationFitOptions& options = {});

/// One reading of a map cell (any stable id: the SLAM grid cell the beam ended in).
struct IntensityObservation {
  uint64_t cell_id = 0;
  float range_m = 0.0f;        ///< metres
  float cos_incidence = 0.0f;  ///< cosine of the angle between beam and surface normal
  float intensity = 0.0f;      ///< raw reading, scanner counts
};

struct SelfCalibrationOptions {
  CalibrationFitOptions fit;
  /// Cells with fewer usable readings carry no information on g and are left out, ≥ 2.
  int min_views_per_cell = 3;
  /// Normalisation of the unobservable scale: the median reflectivity of the
  /// cells used, > 0. 0.5 keeps a building's surfaces within about [0, 1].
  double median_reflectivity = 0.5;
};

/// Self-calibration: the same cell seen from many ranges and angles.
/// @throws std::invalid_argument for bad options or fewer than fit.min_readings
///         usable readings in cells with enough views
IntensityCalibration selfCalibrate(const std::vector<IntensityObservation>& observations,
                                   const SelfCalibrationOptions& options = {});

}  // namespace rmap::slam2d
