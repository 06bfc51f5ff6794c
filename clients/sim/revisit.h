#pragma once
/// @file revisit.h
/// Revisit sequences for place recognition: a carrier drives a closed path
/// several times (laps) and the true poses say which frames show the same
/// place (the ground-truth loop pairs the loop-closure literature scores
/// against).

#include <Eigen/Geometry>
#include <cstdint>
#include <utility>
#include <vector>

namespace rmap::sim {

struct RevisitOptions {
  int laps = 2;                    ///< [1, 100]
  double step_m = 0.5;             ///< travel between frames, metres, > 0
  double corner_radius_m = 1.0;    ///< corners of the path are rounded with this radius, metres, ≥ 0
  double sensor_height_m = 1.0;    ///< above z = 0, metres
  double lateral_offset_m = 0.15;  ///< amplitude of a sideways weave (wavelength 7 m, random phase per lap), metres, ≥ 0
  double heading_jitter_rad = 0.03;///< uniform heading noise per frame, rad, ≥ 0

  /// @throws std::invalid_argument naming the first bad parameter
  void validate() const;
};

struct RevisitFrame {
  Eigen::Isometry3d pose_world;  ///< sensor (x forward, y left, z up, level) → world
  int lap = 0;                   ///< 0-based
  double travel_m = 0.0;         ///< path length driven before this frame (along the centre path)
};

/// Frames every step_m along `path_m` (a closed polygon, counter-clockwise,
/// each corner a left turn, corners rounded), laps times around, heading along
/// the path. Deterministic given the seed.
/// @throws std::invalid_argument for bad options, fewer than 3 corners, a
///         right turn, or a corner radius the edges are too short for
std::vector<RevisitFrame> planRevisits(const std::vector<Eigen::Vector2d>& path_m, const RevisitOptions& options,
                                       uint64_t seed);

struct LoopTruthOptions {
  double max_distance_m = 1.0;   ///< horizontal distance of the same place, metres, > 0
  double max_heading_rad = 0.8;  ///< heading difference of the same view (46°: a 70° camera view still shares a third), rad, > 0
  double min_travel_m = 10.0;    ///< driven between the two frames at least (not just the next frame), metres, ≥ 0

  /// @throws std::invalid_argument naming the first bad parameter
  void validate() const;
};

/// Every (query, reference) frame index pair, query > reference, that shows the
/// same place: within max_distance_m and max_heading_rad, at least
/// min_travel_m apart along the drive. Sorted by query, then reference. O(n²).
/// @throws std::invalid_argument for bad options
std::vector<std::pair<int64_t, int64_t>> truthLoopPairs(const std::vector<RevisitFrame>& frames,
                                                        const LoopTruthOptions& options = {});

}  // namespace rmap::sim
