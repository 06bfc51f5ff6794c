#pragma once
/// @file occupancy_params.h
/// Parameters of the occupancy update and of cuboid fusion.
/// Defaults equal OctoMap 1.9's so both maps are comparable cell for cell.

#include <cmath>

namespace rmap::map3d {

/// Log-odds of a probability, in float as OctoMap stores it.
inline float logOdds(double probability) { return static_cast<float>(std::log(probability / (1.0 - probability))); }
inline double probability(double log_odds) { return 1.0 - 1.0 / (1.0 + std::exp(log_odds)); }

/// How a scan updates the map.
enum class SensorModel {
  kBeam,      ///< cells crossed by a ray become freer, the endpoint cell more occupied
  kEndpoint,  ///< only endpoint cells are updated; free space is not modelled
};

/// How a scan's rays clear free space.
enum class FreeSpaceTracing {
  /// Every ray walked in full from the sensor, with OctoMap's arithmetic: the
  /// same cells as OctoMap's insertPointCloud.
  kOctomapExact,
  /// Every ray walked from its end back towards the sensor until it has met a
  /// run of consecutive cells that earlier rays of the same scan freed: its
  /// path has merged with theirs, and near the sensor rays crowd the same
  /// cells, so most of each walk is skipped. The run is a quarter of the cells
  /// left to the sensor, at least 2 and at most `stop_after_freed_cells`. Where two merged
  /// paths would still part by a cell on the way to the sensor, that cell is
  /// not freed by this ray; docs/BENCHMARKS.md measures the effect against
  /// OctoMap (agreement ≥ 0.998 with the default run length).
  kStopAtFreed,
};

struct OccupancyParams {
  float hit_log_odds = logOdds(0.7);        ///< added to an endpoint cell (+0.85)
  float miss_log_odds = logOdds(0.4);       ///< added to a traversed cell (−0.41)
  float clamp_min_log_odds = logOdds(0.1192);  ///< lower clamp (≈ −2.0)
  float clamp_max_log_odds = logOdds(0.971);   ///< upper clamp (≈ +3.5)
  /// A cell is occupied when its log-odds is >= this (OctoMap's isNodeOccupied);
  /// values exactly at 0 do not arise from the default updates.
  float occupied_threshold_log_odds = 0.0f;
  /// metres; < 0 means unlimited. Longer rays clear space up to this range and
  /// mark no endpoint.
  double max_range_m = -1.0;
  SensorModel sensor_model = SensorModel::kBeam;
  FreeSpaceTracing free_space_tracing = FreeSpaceTracing::kStopAtFreed;
  /// kStopAtFreed: the longest run of already freed cells a walk needs before
  /// it stops, >= 2. Larger is closer to exact and slower.
  int stop_after_freed_cells = 16;
};

struct FusionParams {
  /// Cells of one cuboid share their state and their log-odds span at most
  /// this much; the cuboid stores the middle of the span, so no cell moves by
  /// more than half of it. 0 keeps the map bit-identical to the unfused one.
  float tolerance_log_odds = 0.25f;
  /// A block is fused when this many scans passed without touching it; 0
  /// fuses every block right after each scan.
  int fuse_after_scans = 4;
};

}  // namespace rmap::map3d
