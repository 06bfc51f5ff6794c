#include "slam2d/self_calibration.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace rmap::slam2d {
namespace {


/// One usable reading in log space, tagged with its surface patch.
struct LogReading {
  uint32_t patch;
  double log_r;
  double alpha_deg;
  double log_i;
};

/// Turns a reading into log space; false when it cannot enter a fit.
bool toLogReading(uint32_t patch, double range_m, double cos_incidence, double intensity, double max_incidence_deg,
                  LogReading& out) {
  if (!(range_m > 0.0) || !std::isfinite(range_m) || !(intensity > 0.0) || !std::isfinite(intensity)) return false;
  if (!(cos_incidence > 0.0 && cos_incidence <= 1.0 + 1e-6)) return false;
  const double alpha = std::acos(std::min(1.0, cos_incidence)) * (180.0 / std::numbers::pi);
  if (alpha > max_incidence_deg) return false;
  out = {patch, std::log(range_m), alpha, std::log(intensity)};
  return true;
}

void validate(const CalibrationFitOptions& o) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("intensity calibration fit: " + what); };
  if (!(o.range_knot_step > 0.0) || !std::isfinite(o.range_knot_step)) fail("range_knot_step must be > 0");
  if (!(o.incidence_knot_step_deg > 0.0) || !std::isfinite(o.incidence_knot_step_deg)) {
    fail("incidence_knot_step_deg must be > 0");
  }
  if (!(o.max_incidence_deg > 0.0 && o.max_incidence_deg < 90.0)) fail("max_incidence_deg must be in (0, 90)");
  if (!(o.smoothness >= 0.0) || !std::isfinite(o.smoothness)) fail("smoothness must be ≥ 0");
  if (!std::isnan(o.saturation) && !(o.saturation > 0.0)) fail("saturation must be > 0 (or NaN to detect it)");
  if (o.robust_iterations < 0) fail("robust_iterations must be ≥ 0");
  if (o.min_readings < 1) fail("min_readings must be ≥ 1");
  if (!(o.min_response_fraction >= 0.0 && o.min_response_fraction < 1.0)) fail("min_response_fraction must be in [0, 1)");
}

double median(std::vector<double> v) {
  auto mid = v.begin() + v.size() / 2;
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

struct LogModelFit {
  IntensityCalibration calibration;
  std::vector<double> log_reflectivity;  ///< per patch: known, estimated, or NaN without readings
  double sigma = 0.0;                    ///< robust scale of the log residuals (≈ relative noise)
};

/// Second-difference penalty λ·DᵀD on the coefficient block starting at `offset`.
void addSecondDifferencePenalty(Eigen::MatrixXd& a, int offset, int n, double lambda) {
  for (int k = 0; k + 2 < n; ++k) {
    const int idx[3] = {offset + k, offset + k + 1, offset + k + 2};
    const double d[3] = {1.0, -2.0, 1.0};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) a(idx[i], idx[j]) += lambda * d[i] * d[j];
    }
  }
}

/// Fits ln I = ln ρ_patch + R(ln r) + A(α) (file comment of self_calibration.h).
/// @param known_log_rho  per patch: ln ρ when known, NaN when it is estimated
LogModelFit fitLogModel(const std::vector<LogReading>& readings, const std::vector<double>& known_log_rho,
                        double saturation, const CalibrationFitOptions& o) {
  double lr_lo = readings[0].log_r, lr_hi = lr_lo, alpha_hi = 0.0;
  for (const LogReading& r : readings) {
    lr_lo = std::min(lr_lo, r.log_r);
    lr_hi = std::max(lr_hi, r.log_r);
    alpha_hi = std::max(alpha_hi, r.alpha_deg);
  }
  if (lr_hi - lr_lo < 1e-3) lr_hi = lr_lo + 1e-3;  // one range only: a sliver of support
  alpha_hi = std::max(alpha_hi, 0.5);
  const int n_r = std::max(4, static_cast<int>(std::ceil((lr_hi - lr_lo) / o.range_knot_step)) + 3);
  const int n_a = std::max(4, static_cast<int>(std::ceil(alpha_hi / o.incidence_knot_step_deg)) + 3);
  const int n = n_r + n_a;
  CubicBSpline range_spline{lr_lo, lr_hi, std::vector<double>(n_r, 0.0)};
  CubicBSpline incidence_spline{0.0, alpha_hi, std::vector<double>(n_a, 0.0)};

  const size_t count = readings.size();
  std::vector<int> first_r(count), first_a(count);
  std::vector<std::array<double, 4>> w_r(count), w_a(count);
  for (size_t j = 0; j < count; ++j) {
    first_r[j] = range_spline.basis(readings[j].log_r, w_r[j]);
    first_a[j] = n_r + incidence_spline.basis(readings[j].alpha_deg, w_a[j]);
  }
  // Readings grouped by patch, so each unknown patch is eliminated in one pass.
  std::vector<size_t> order(count);
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return readings[a].patch < readings[b].patch; });
  bool any_unknown = false;
  for (const LogReading& r : readings) any_unknown |= std::isnan(known_log_rho[r.patch]);

  std::vector<double> weight(count, 1.0);
  std::vector<double> log_rho = known_log_rho;
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(n);
  Eigen::MatrixXd a(n, n);
  Eigen::VectorXd b(n), s(n);
  std::vector<int> touched;
  std::vector<char> is_touched(n, 0);
  std::vector<double> residual(count);
  double sigma = 0.0;

  for (int iteration = 0; iteration <= o.robust_iterations; ++iteration) {
    a.setZero();
    b.setZero();
    double total_weight = 0.0;
    for (size_t begin = 0; begin < count;) {
      const uint32_t patch = readings[order[begin]].patch;
      size_t end = begin;
      while (end < count && readings[order[end]].patch == patch) ++end;
      const bool unknown = std::isnan(known_log_rho[patch]);
      double patch_weight = 0.0, patch_t = 0.0;
      for (size_t q = begin; q < end; ++q) {
        const size_t j = order[q];
        const double w = weight[j];
        const double y = readings[j].log_i - (unknown ? 0.0 : known_log_rho[patch]);
        int idx[8];
        double phi[8];
        for (int k = 0; k < 4; ++k) {
          idx[k] = first_r[j] + k, phi[k] = w_r[j][k];
          idx[4 + k] = first_a[j] + k, phi[4 + k] = w_a[j][k];
        }
        for (int p = 0; p < 8; ++p) {
          b(idx[p]) += w * phi[p] * y;
          for (int q2 = 0; q2 < 8; ++q2) a(idx[p], idx[q2]) += w * phi[p] * phi[q2];
        }
        total_weight += w;
        if (!unknown) continue;
        patch_weight += w;
        patch_t += w * y;
        for (int p = 0; p < 8; ++p) {
          if (!is_touched[idx[p]]) is_touched[idx[p]] = 1, touched.push_back(idx[p]), s(idx[p]) = 0.0;
          s(idx[p]) += w * phi[p];
        }
      }
      if (unknown && patch_weight > 0.0) {  // Schur complement of the patch's ln ρ
        for (int p : touched) {
          b(p) -= s(p) * patch_t / patch_weight;
          for (int q2 : touched) a(p, q2) -= s(p) * s(q2) / patch_weight;
        }
      }
      for (int p : touched) is_touched[p] = 0;
      touched.clear();
      begin = end;
    }

    const double mean_weight = total_weight / n;
    addSecondDifferencePenalty(a, 0, n_r, o.smoothness * total_weight / n_r);
    addSecondDifferencePenalty(a, n_r, n_a, o.smoothness * total_weight / n_a);
    // Gauges: A(0) = 0 always; R(middle of the support) = 0 when the scale is unobservable.
    auto constrain = [&](int first, const std::array<double, 4>& w) {
      const double big = 1e6 * mean_weight;
      for (int p = 0; p < 4; ++p) {
        for (int q2 = 0; q2 < 4; ++q2) a(first + p, first + q2) += big * w[p] * w[q2];
      }
    };
    std::array<double, 4> w0;
    constrain(n_r + incidence_spline.basis(0.0, w0), w0);
    if (any_unknown) constrain(range_spline.basis(0.5 * (lr_lo + lr_hi), w0), w0);
    a.diagonal().array() += 1e-9 * mean_weight;
    theta = a.ldlt().solve(b);

    // Patch reflectivities and residuals for the next weights.
    for (size_t begin = 0; begin < count;) {
      const uint32_t patch = readings[order[begin]].patch;
      size_t end = begin;
      while (end < count && readings[order[end]].patch == patch) ++end;
      double patch_weight = 0.0, patch_sum = 0.0;
      for (size_t q = begin; q < end; ++q) {
        const size_t j = order[q];
        double model = 0.0;
        for (int k = 0; k < 4; ++k) model += w_r[j][k] * theta(first_r[j] + k) + w_a[j][k] * theta(first_a[j] + k);
        residual[j] = readings[j].log_i - model;
        patch_weight += weight[j];
        patch_sum += weight[j] * residual[j];
      }
      if (std::isnan(known_log_rho[patch])) log_rho[patch] = patch_sum / patch_weight;
      for (size_t q = begin; q < end; ++q) residual[order[q]] -= log_rho[patch];
      begin = end;
    }
    std::vector<double> abs_residual(count);
    for (size_t j = 0; j < count; ++j) abs_residual[j] = std::abs(residual[j]);
    sigma = std::max(1e-6, 1.4826 * median(abs_residual));
    for (size_t j = 0; j < count; ++j) {
      const double z = residual[j] / (2.385 * sigma);  // Cauchy, 95 % efficiency at the normal
      weight[j] = 1.0 / (1.0 + z * z);
    }
  }

  for (int k = 0; k < n_r; ++k) range_spline.coefficients[k] = theta(k);
  for (int k = 0; k < n_a; ++k) incidence_spline.coefficients[k] = theta(n_r + k);
  // Largest g over the support (separable: the sum of both maxima), sampled finely.
  double max_r = -std::numeric_limits<double>::infinity(), max_a = max_r;
  for (int i = 0; i <= 512; ++i) {
    max_r = std::max(max_r, range_spline(lr_lo + (lr_hi - lr_lo) * i / 512.0));
    max_a = std::max(max_a, incidence_spline(alpha_hi * i / 512.0));
  }
  const double min_response = o.min_response_fraction * std::exp(max_r + max_a);
  return {IntensityCalibration(std::move(range_spline), std::move(incidence_spline), saturation, min_response),
          std::move(log_rho), sigma};
}

/// Readings below a saturation level, in patches with at least min_views of them (0: any patch).
std::vector<LogReading> unsaturated(const std::vector<LogReading>& all, double level, size_t patches, int min_views) {
  const double log_level = std::log(level);
  std::vector<int> views(patches, 0);
  for (const LogReading& r : all) views[r.patch] += r.log_i < log_level;
  std::vector<LogReading> out;
  for (const LogReading& r : all) {
    if (r.log_i < log_level && views[r.patch] >= min_views) out.push_back(r);
  }
  return out;
}

/// Fits on the unsaturated readings. A given level is taken as is; a
/// detected pile (detectSaturation) must also be confirmed by the fit: the
/// readings above it must fall short of what their patch and g predict (a
/// clipped reading reads less than the light it got), else a natural crowd
/// of bright readings, e.g. at the range where g peaks, would be discarded.
LogModelFit fitUnsaturated(const std::vector<LogReading>& all, const std::vector<double>& known_log_rho, int min_views,
                           const CalibrationFitOptions& o, const char* what) {
  double level = o.saturation;
  bool detected = false;
  if (std::isnan(level)) {
    std::vector<float> intensities;
    intensities.reserve(all.size());
    for (const LogReading& r : all) intensities.push_back(static_cast<float>(std::exp(r.log_i)));
    level = detectSaturation(intensities);
    detected = std::isfinite(level);
  }
  auto fit = [&](double saturation) {
    const std::vector<LogReading> readings = unsaturated(all, saturation, known_log_rho.size(), min_views);
    if (readings.size() < o.min_readings) {
      throw std::invalid_argument(std::string(what) + ": " + std::to_string(readings.size()) +
                                  " usable readings, need " + std::to_string(o.min_readings));
    }
    return fitLogModel(readings, known_log_rho, saturation, o);
  };
  LogModelFit result = fit(level);
  if (!detected) return result;
  // ln(I / predicted) of the readings at or above the level (the pile) and
  // of those just below it (the control: same selection, same outliers).
  const double log_level = std::log(level), clearly_short = -std::max(0.05, 3.0 * result.sigma);
  size_t pile = 0, pile_short = 0, control = 0, control_short = 0;
  for (const LogReading& r : all) {
    const double log_rho = result.log_reflectivity[r.patch];
    if (r.log_i < log_level - 0.3 || !std::isfinite(log_rho)) continue;
    const bool short_of_g = r.log_i - log_rho - result.calibration.logRange()(r.log_r) -
                                result.calibration.logIncidence()(r.alpha_deg) < clearly_short;
    if (r.log_i >= log_level) pile++, pile_short += short_of_g;
    else control++, control_short += short_of_g;
  }
  // Confirmed when at least 5 % of the pile reads clearly (3σ) less than
  // predicted and three times as often as the control does; fewer than ten
  // readings in the pile cannot refute it.
  constexpr size_t kFewest = 10;
  const double pile_rate = pile ? double(pile_short) / pile : 0.0;
  const double control_rate = control ? double(control_short) / control : 0.0;
  if (pile >= kFewest && !(pile_rate >= 0.05 && pile_rate > 3.0 * control_rate)) {
    result = fit(std::numeric_limits<double>::infinity());
  }
  return result;
}

}  // namespace

double detectSaturation(const std::vector<float>& intensities) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  constexpr int kBins = 100;               // over ln(I / max) ∈ [−1, 0]
  constexpr double kBin = 1.0 / kBins;
  constexpr double kMaxPileSigma = 0.15;   // receiver noise at saturation, relative
  double max_i = 0.0;
  for (float v : intensities) {
    if (std::isfinite(v)) max_i = std::max(max_i, double(v));
  }
  if (!(max_i > 0.0)) return kInf;
  std::vector<double> x;  // ln(I / max) of the readings within a factor e of the largest
  size_t positive = 0;
  for (float v : intensities) {
    if (!(v > 0.0f) || !std::isfinite(v)) continue;
    ++positive;
    const double l = std::log(v / max_i);
    if (l >= -1.0) x.push_back(l);
  }
  std::vector<int> histogram(kBins, 0);
  for (double l : x) ++histogram[std::clamp(static_cast<int>((l + 1.0) / kBin), 0, kBins - 1)];
  int peak = 0, peak_count = -1;
  for (int i = 0; i < kBins; ++i) {  // 5-bin box filter: one noisy bin is no peak
    int sum = 0;
    for (int k = std::max(0, i - 2); k <= std::min(kBins - 1, i + 2); ++k) sum += histogram[k];
    if (sum >= peak_count) peak = i, peak_count = sum;  // ≥: the highest of equal peaks
  }
  // The pile's centre: median of the readings under the peak window (an exact clip sits at the edge).
  std::vector<double> window;
  const double window_lo = -1.0 + (peak - 2) * kBin, window_hi = -1.0 + (peak + 3) * kBin;
  for (double l : x) {
    if (l >= window_lo && l <= window_hi) window.push_back(l);
  }
  const double center = median(window);
  double upper_sq = 0.0;
  int upper = 0;
  for (double l : x) {
    if (l > center) upper_sq += (l - center) * (l - center), ++upper;
  }
  const double sigma = std::max(0.5 * kBin, upper > 0 ? std::sqrt(upper_sq / upper) : 0.0);
  if (sigma > kMaxPileSigma) return kInf;
  const double threshold = center - 3.0 * sigma;
  // A peak: twice as dense as the readings in an equally wide window just below the pile.
  size_t in_pile = 0, below = 0;
  for (double l : x) {
    if (l >= threshold) ++in_pile;
    else if (l >= 2.0 * threshold) ++below;
  }
  const double peak_density = peak_count / (5.0 * kBin), below_density = below / -threshold;
  const bool pile = in_pile >= std::max<size_t>(20, positive / 1000) && peak_density > 2.0 * below_density;
  return pile ? max_i * std::exp(threshold) : kInf;
}

IntensityCalibration fitCalibration(const std::vector<ReflectivityObservation>& observations,
                                    const CalibrationFitOptions& options) {
  validate(options);
  std::vector<LogReading> readings;
  std::vector<double> known_log_rho;
  for (const ReflectivityObservation& o : observations) {
    LogReading r;
    if (!(o.reflectivity > 0.0f) || !std::isfinite(o.reflectivity)) continue;
    if (!toLogReading(static_cast<uint32_t>(readings.size()), o.range_m, o.cos_incidence, o.intensity,
                      options.max_incidence_deg, r)) {
      continue;
    }
    readings.push_back(r);
    known_log_rho.push_back(std::log(double(o.reflectivity)));
  }
  return fitUnsaturated(readings, known_log_rho, 0, options, "fitCalibration").calibration;
}

IntensityCalibration selfCalibrate(const std::vector<IntensityObservation>& observations,
                                   const SelfCalibrationOptions& options) {
  validate(options.fit);
  if (options.min_views_per_cell < 2) throw std::invalid_argument("selfCalibrate: min_views_per_cell must be ≥ 2");
  if (!(options.median_reflectivity > 0.0) || !std::isfinite(options.median_reflectivity)) {
    throw std::invalid_argument("selfCalibrate: median_reflectivity must be > 0");
  }
  std::unordered_map<uint64_t, uint32_t> patch_of;
  std::vector<LogReading> readings;
  for (const IntensityObservation& o : observations) {
    const auto [it, added] = patch_of.try_emplace(o.cell_id, static_cast<uint32_t>(patch_of.size()));
    LogReading r;
    if (toLogReading(it->second, o.range_m, o.cos_incidence, o.intensity, options.fit.max_incidence_deg, r)) {
      readings.push_back(r);
    }
  }
  const LogModelFit fit = fitUnsaturated(readings, std::vector<double>(patch_of.size(), std::numeric_limits<double>::quiet_NaN()),
                                         options.min_views_per_cell, options.fit, "selfCalibrate");
  std::vector<double> cell_log_rho;
  for (double l : fit.log_reflectivity) {
    if (std::isfinite(l)) cell_log_rho.push_back(l);
  }
  return fit.calibration.scaled(std::exp(median(cell_log_rho)) / options.median_reflectivity);
}

}  // namespace rmap::slam2d
