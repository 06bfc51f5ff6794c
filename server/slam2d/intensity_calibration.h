#pragma once
/// @file intensity_calibration.h
/// The response of a laser scanner's intensity channel to range and angle of
/// incidence, g(r, α): the raw intensity a surface of reflectivity 1 returns.
/// Dividing a reading by it gives a reflectivity that does not depend on
/// where the robot stood: ρ = I / g(r, α).
///
/// Model: ln g(r, α) = R(ln r) + A(α), two uniform cubic B-splines. The
/// separable form holds because range (beam spread, receiver gain control,
/// the near-range blind zone of bistatic optics) and incidence (the surface's
/// scattering) act on different factors of the received power; it needs data
/// spread along each axis, not over the whole (r, α) plane, which a robot
/// driving through a building provides. Splines over ln r and α represent a
/// power law, a near-range drop and a cosᵏ or non-Lambertian falloff alike, so
/// scanners with very different receivers share one model. The gauge between
/// the two splines is A(0) = 0: R(ln r) is the response at normal incidence.
///
/// Fitting (from targets or from the map alone) is in self_calibration.h.
///
/// Text format (toText/fromText), one record per line, '#' starts a comment,
/// blank lines are ignored, keys in any order after the version line, each
/// exactly once, numbers in C locale:
///
///   rmap_intensity_calibration 1
///   range_m <min> <max>              support in range, metres, 0 < min < max
///   max_incidence_deg <deg>          support in incidence: α ∈ [0, deg], (0, 90)
///   saturation <counts>|none         readings ≥ counts are saturated
///   min_response <counts>            g below this gives no reflectivity, ≥ 0
///   log_range <n> <c1> … <cn>        R over ln r ∈ [ln min, ln max], n ≥ 4
///   log_incidence <n> <c1> … <cn>    A over α ∈ [0, max_incidence_deg] in degrees, n ≥ 4
///
/// A spline with n coefficients c₁…cₙ over [lo, hi] has n − 3 equal segments
/// of width h; at x in segment s (from 0) with t = (x − lo)/h − s it is
/// Σₖ cₛ₊ₖ·Bₖ(t), k = 0…3, with the uniform cubic B-spline weights
/// B₀ = (1−t)³/6, B₁ = (3t³ − 6t² + 4)/6, B₂ = (−3t³ + 3t² + 3t + 1)/6, B₃ = t³/6.

#include <array>
#include <string>
#include <vector>

namespace rmap::slam2d {

/// Uniform cubic B-spline over [lo, hi] (layout above); x is clamped to the interval.
struct CubicBSpline {
  double lo = 0.0;
  double hi = 1.0;
  std::vector<double> coefficients;  ///< ≥ 4

  /// The four non-zero basis weights at x; returns the index of the first coefficient they apply to.
  int basis(double x, std::array<double, 4>& weights) const;
  double operator()(double x) const;
};

/// One reading of a surface whose reflectivity is known (a calibration target).
struct ReflectivityObservation {
  float reflectivity = 0.0f;   ///< ρ of the surface, > 0
  float range_m = 0.0f;        ///< metres
  float cos_incidence = 0.0f;  ///< cosine of the angle between beam and surface normal
  float intensity = 0.0f;      ///< raw reading, scanner counts
};

/// g(r, α): the raw intensity a surface of reflectivity 1 gives at range r
/// and incidence α, learned from data; ρ = I / g(r, α).
class IntensityCalibration {
 public:
  /// An empty calibration: response and reflectivity are NaN everywhere.
  IntensityCalibration() = default;
  /// @param log_range      R over ln r; its interval is the range support (metres after exp)
  /// @param log_incidence  A over α in degrees; lo must be 0, hi is the incidence support
  /// @param saturation     counts, > 0; readings at or above are saturated (+inf: never)
  /// @param min_response   counts, ≥ 0; where g is below, reflectivity is NaN
  /// @throws std::invalid_argument for a bad spline or limit, naming it
  IntensityCalibration(CubicBSpline log_range, CubicBSpline log_incidence, double saturation, double min_response);

  bool empty() const { return log_range_.coefficients.empty(); }
  /// Support in range, metres.
  double minRange_m() const;
  double maxRange_m() const;
  /// Support in incidence, degrees from the normal.
  double maxIncidence_deg() const { return log_incidence_.hi; }
  double saturation() const { return saturation_; }
  double minResponse() const { return min_response_; }
  const CubicBSpline& logRange() const { return log_range_; }
  const CubicBSpline& logIncidence() const { return log_incidence_; }

  /// g in counts at range_m (metres) and cos_incidence; NaN outside the support.
  double response(double range_m, double cos_incidence) const;
  /// ρ = intensity / g. NaN outside the ranges/angles the calibration was
  /// learned on, for a saturated or negative or non-finite reading, or where
  /// g < minResponse().
  double reflectivity(double intensity, double range_m, double cos_incidence) const;

  /// The same shape with g multiplied by factor (> 0): reflectivities divide by it.
  /// @throws std::invalid_argument for a factor that is not finite and > 0
  IntensityCalibration scaled(double factor) const;
  /// Sets the absolute scale from readings of a target of known reflectivity
  /// (self-calibration fixes the shape only): g is scaled by the median of
  /// I / (ρ·g) over the readings inside the support.
  /// @throws std::invalid_argument when no reading is usable
  IntensityCalibration anchoredTo(const std::vector<ReflectivityObservation>& reference) const;

  /// Text in the format above; numbers round-trip exactly.
  std::string toText() const;
  /// @throws std::invalid_argument "intensity calibration line N: ..." for
  ///         the first wrong line (or "...: missing <key>" at the end)
  static IntensityCalibration fromText(const std::string& text);

 private:
  CubicBSpline log_range_;
  CubicBSpline log_incidence_;
  double saturation_ = 0.0;
  double min_response_ = 0.0;
};

}  // namespace rmap::slam2d
