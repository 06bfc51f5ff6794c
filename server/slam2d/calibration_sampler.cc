#include "slam2d/calibration_sampler.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace rmap::slam2d {

namespace {
constexpr float kRadToDeg = static_cast<float>(180.0 / std::numbers::pi);
float degreesBetween(float cos_a, float cos_b) {
  return std::abs(std::acos(std::clamp(cos_a, 0.0f, 1.0f)) - std::acos(std::clamp(cos_b, 0.0f, 1.0f))) * kRadToDeg;
}
}  // namespace

void CalibrationSampler::add(uint64_t cell_id, float range_m, float cos_incidence, float intensity) {
  if (full() || !(range_m > 0.0f) || !std::isfinite(range_m) || !(intensity > 0.0f) || !std::isfinite(intensity) ||
      !(cos_incidence > 0.0f) || !(cos_incidence <= 1.0f))
    return;
  CellViews& c = cells_[cell_id];
  if (c.count >= options_.max_views_per_cell) return;
  if (c.count > 0) {
    const bool new_range = std::abs(std::log(range_m / c.last_range_m)) >= 0.05f;
    if (!new_range && degreesBetween(cos_incidence, c.last_cos) < 3.0f) return;
    c.min_range_m = std::min(c.min_range_m, range_m), c.max_range_m = std::max(c.max_range_m, range_m);
    c.min_cos = std::min(c.min_cos, cos_incidence), c.max_cos = std::max(c.max_cos, cos_incidence);
  } else {
    c.min_range_m = c.max_range_m = range_m;
    c.min_cos = c.max_cos = cos_incidence;
  }
  c.last_range_m = range_m, c.last_cos = cos_incidence;
  ++c.count;
  observations_.push_back({cell_id, range_m, cos_incidence, intensity});
  if (!c.well_seen && c.count >= options_.min_views &&
      (c.max_range_m >= 1.3f * c.min_range_m || degreesBetween(c.min_cos, c.max_cos) >= 15.0f)) {
    c.well_seen = true;
    ++well_seen_;
  }
}

bool CalibrationSampler::ready() const {
  return well_seen_ >= required_cells_ && observations_.size() >= options_.min_observations;
}

}  // namespace rmap::slam2d
