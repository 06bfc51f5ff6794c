#pragma once
/// @file intensity.h
/// Return-intensity response shared by the simulated 3D lidar and 2D laser.
///
/// Ideal (Lambertian target, ideal receiver):  I ∝ ρ · cos α / r².
/// Real receivers differ, and calibration work needs those differences:
///
///   I(ρ, r, α) = min(saturation, gain · ρ · cosᵏ α · (1 − exp(−(r / near_range_m)^q)) / r^e) · (1 + σ·n)
///
/// with ρ the surface reflectivity in [0, 1], r the range in metres, α the
/// angle between the beam and the surface normal, k = incidence_exponent,
/// e = range_exponent (≠ 2 models receiver gain control and beam divergence),
/// the near factor (q = near_exponent) models the bistatic optics' blind zone:
/// the return spot leaves the detector below a metre or two, so intensity
/// rises with range up to about near_range_m before falling; n ~ N(0, 1), σ =
/// noise_rel_sigma; the noisy value is clamped at 0. Units are the scanner's
/// arbitrary counts.

#include <algorithm>
#include <cmath>
#include <random>

namespace rmap::sim {

struct IntensityModel {
  double gain = 800.0;               ///< counts·m^e for ρ = 1 at normal incidence, > 0
  double range_exponent = 1.8;       ///< e, > 0
  double incidence_exponent = 1.0;   ///< k, ≥ 0 (1: Lambertian)
  double near_range_m = 1.5;         ///< metres, > 0; the near factor is 0.63 here, ≈ 1 at twice it
  double near_exponent = 4.0;        ///< q, > e so the response really drops near the sensor
  double saturation = 255.0;         ///< counts, > 0; receiver clipping
  double noise_rel_sigma = 0.03;     ///< σ of the multiplicative noise, ≥ 0

  /// Noise-free response; cos_incidence is clamped to [0, 1].
  /// @param range_m  metres; ≤ 0 gives 0 (no light reaches a detector inside the target)
  double expected(double reflectivity, double range_m, double cos_incidence) const {
    if (!(range_m > 0.0)) return 0.0;
    const double c = std::clamp(cos_incidence, 0.0, 1.0);
    const double near = 1.0 - std::exp(-std::pow(range_m / near_range_m, near_exponent));
    const double ideal = gain * reflectivity * std::pow(c, incidence_exponent) * near / std::pow(range_m, range_exponent);
    return std::min(saturation, ideal);
  }

  /// expected() with multiplicative noise drawn from rng (one normal draw).
  template <class Rng>
  double sample(double reflectivity, double range_m, double cos_incidence, Rng& rng) const {
    std::normal_distribution<double> unit(0.0, 1.0);
    const double noise = unit(rng);
    return std::max(0.0, expected(reflectivity, range_m, cos_incidence) * (1.0 + noise_rel_sigma * noise));
  }

  /// @throws std::invalid_argument naming the first bad parameter
  void validate() const;
};

}  // namespace rmap::sim
