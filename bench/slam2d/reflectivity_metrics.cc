#include "slam2d/reflectivity_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>

#include "slam2d/incidence.h"

namespace rmap::bench {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr size_t kMinViews = 5;

double median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  const auto mid = v.begin() + v.size() / 2;
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

double coefficientOfVariation(const std::vector<double>& v) {
  double sum = 0.0, sum2 = 0.0;
  for (double x : v) {
    sum += x;
    sum2 += x * x;
  }
  const double n = double(v.size()), mean = sum / n;
  return mean > 0.0 ? std::sqrt(std::max(0.0, sum2 / n - mean * mean)) / mean : kNaN;
}

struct CellReadings {
  Eigen::Vector2i cell;
  std::vector<double> raw, calibrated, truth;
};

uint64_t key(const Eigen::Vector2i& c) { return (uint64_t(uint32_t(c.x())) << 32) | uint32_t(c.y()); }

}  // namespace

ReflectivityFigures reflectivityFigures(const Slam2dDataset& data, const std::vector<slam2d::Pose2>& laser_poses,
                                        const slam2d::Slam2d& slam) {
  if (laser_poses.size() != data.inputs.size()) {
    throw std::invalid_argument("reflectivityFigures: " + std::to_string(laser_poses.size()) + " poses for " +
                                std::to_string(data.inputs.size()) + " scans");
  }
  std::unordered_map<uint64_t, CellReadings> cells;
  bool calibrated = false;
  size_t r = 0;
  while (r < data.sim_returns.size()) {
    const uint32_t k = data.sim_returns[r].scan;
    const slam2d::LaserScan& scan = data.inputs[k].scan;
    const slam2d::IntensityCalibration* calibration = slam.calibration(scan.model);
    calibrated |= calibration != nullptr;
    const std::vector<float> cos_incidence =
        calibration ? slam2d::cosIncidence(scan, slam.options().incidence) : std::vector<float>{};
    for (; r < data.sim_returns.size() && data.sim_returns[r].scan == k; ++r) {
      const SimReturn& ret = data.sim_returns[r];
      const float range = scan.ranges_m[ret.beam], angle = scan.angles_rad[ret.beam];
      const Eigen::Vector2i cell =
          slam.grid().cellOf(laser_poses[k] * Eigen::Vector2d(range * std::cos(angle), range * std::sin(angle)));
      CellReadings& c = cells[key(cell)];
      c.cell = cell;
      const double intensity = scan.intensities[ret.beam];
      c.raw.push_back(intensity);
      c.truth.push_back(ret.true_reflectivity);
      if (calibration) {
        const double rho = calibration->reflectivity(intensity, range, cos_incidence[ret.beam]);
        if (std::isfinite(rho)) c.calibrated.push_back(rho);
      }
    }
  }

  ReflectivityFigures f;
  std::vector<double> spread_raw, spread_calibrated, ratios;
  std::vector<std::pair<double, double>> mapped_truth;  // (ρ_map, ρ_true)
  for (const auto& [k, c] : cells) {
    if (c.raw.size() >= kMinViews && (!calibrated || c.calibrated.size() >= kMinViews)) {
      spread_raw.push_back(coefficientOfVariation(c.raw));
      if (calibrated) spread_calibrated.push_back(coefficientOfVariation(c.calibrated));
    }
    const slam2d::ReflectivityCell mapped = slam.grid().reflectivity(c.cell);
    const double truth = median(c.truth);
    if (mapped.count == 0 || !(mapped.mean > 0.0f) || !(truth > 0.0)) continue;
    mapped_truth.emplace_back(mapped.mean, truth);
    ratios.push_back(truth / mapped.mean);
  }
  std::erase_if(spread_raw, [](double v) { return !std::isfinite(v); });
  std::erase_if(spread_calibrated, [](double v) { return !std::isfinite(v); });
  f.cells_spread = spread_raw.size();
  f.spread_raw = median(spread_raw);
  f.spread_calibrated = calibrated ? median(spread_calibrated) : kNaN;
  f.cells_compared = mapped_truth.size();
  f.scale = median(ratios);
  std::vector<double> err, err_unscaled;
  for (const auto& [mapped, truth] : mapped_truth) {
    err.push_back(std::abs(f.scale * mapped - truth) / truth);
    err_unscaled.push_back(std::abs(mapped - truth) / truth);
  }
  f.rel_err_median = median(err);
  f.rel_err_median_unscaled = median(err_unscaled);
  return f;
}

}  // namespace rmap::bench
