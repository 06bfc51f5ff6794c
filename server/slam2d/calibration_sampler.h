#pragma once
/// @file calibration_sampler.h
/// Collects, for one scanner model without a calibration, a bounded sample
/// of intensity readings of map cells seen from varied viewpoints, and says
/// when it holds enough for selfCalibrate.
///
/// A reading of a cell enters only if its viewpoint differs from the last one
/// kept for that cell (range by ≥ 5 % or incidence by ≥ 3°): a robot standing
/// still or creeping adds nothing, so the sample spreads over distinct views.
/// A cell is "well seen" once it holds min_views readings spanning ≥ 30 % in
/// range or ≥ 15° in incidence, which is what separates R(r) and A(α) from the
/// cell's own reflectivity.

#include <cstdint>
#include <unordered_map>
#include <vector>

#include "slam2d/self_calibration.h"

namespace rmap::slam2d {

struct CalibrationSamplerOptions {
  size_t max_observations = 200000;  ///< hard bound of the sample (≈ 3 MB)
  int max_views_per_cell = 16;       ///< a cell stops taking readings then
  int min_views = 3;                 ///< readings that make a cell usable
  size_t min_well_seen_cells = 1500; ///< calibrate once this many cells are well seen ...
  size_t min_observations = 8000;    ///< ... and the sample holds this many readings
};

class CalibrationSampler {
 public:
  explicit CalibrationSampler(CalibrationSamplerOptions options = {}) : options_(options) {}

  /// Offers one reading (finite positive range and intensity, cos incidence in (0, 1]).
  void add(uint64_t cell_id, float range_m, float cos_incidence, float intensity);
  /// Enough for a self-calibration attempt (see the options); after a failed
  /// attempt call postpone(), which doubles the requirement.
  bool ready() const;
  void postpone() { required_cells_ *= 2; }
  /// No more readings are taken (bound reached).
  bool full() const { return observations_.size() >= options_.max_observations; }
  const std::vector<IntensityObservation>& observations() const { return observations_; }

 private:
  struct CellViews {
    int count = 0;
    float last_range_m = 0, last_cos = 0;
    float min_range_m = 0, max_range_m = 0, min_cos = 0, max_cos = 0;
    bool well_seen = false;
  };

  CalibrationSamplerOptions options_;
  std::vector<IntensityObservation> observations_;
  std::unordered_map<uint64_t, CellViews> cells_;
  size_t well_seen_ = 0;
  size_t required_cells_ = options_.min_well_seen_cells;
};

}  // namespace rmap::slam2d
