#pragma once
/// @file reflectivity_patch.h
/// Place images for robots with a 2D laser: a square patch of the 2D map's
/// reflectivity layer around a pose, turned into the robot's heading, so the
/// same place seen again gives the same image whatever the map frame.
///
/// Pixel (row r, column c) of an N×N patch samples the map (nearest cell) at
/// robot-frame point x = (N/2 − r − ½)·pixel_m (forward is up),
/// y = (N/2 − c − ½)·pixel_m (left is left). Grey value:
///  - 0: unknown, or occupancy probability below occupied_probability (free);
///  - occupied: 64 + 191·clamp(ρ / reflectivity_max, 0, 1) with ρ the cell's fused
///    reflectivity mean; 64 when the cell holds no reflectivity yet.
/// The occupancy outline alone carries structure; the reflectivity makes
/// look-alike corridors differ (posters, tape, doors).

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "slam2d/grid_map.h"
#include "slam2d/pose2.h"

namespace rmap::loop {

struct PatchOptions {
  int size_px = 160;                 ///< patch edge in pixels, [32, 4096]
  double pixel_m = 0.05;             ///< pixel edge in metres, > 0 (the default patch spans 8 m)
  double reflectivity_max = 1.0;     ///< ρ shown as white, > 0
  double occupied_probability = 0.5; ///< cells above this count as occupied, (0, 1)

  /// @throws std::invalid_argument naming the first bad parameter
  void validate() const;
};

/// Renders the patch (8-bit, single channel, size_px × size_px). O(size_px²).
/// @throws std::invalid_argument for bad options or a non-finite pose
cv::Mat reflectivityPatch(const slam2d::GridMap2d& map, const slam2d::Pose2& center, const PatchOptions& options);

/// The motion between the centre poses of two patches, from the motion of their pixels.
/// @param reference_from_query_px  rigid motion taking the query patch's pixels (x = column,
///        y = row; pixel centres at integers) onto the reference patch's pixels
/// @return the query patch's centre pose in the reference patch's centre frame (m, rad)
/// @throws std::invalid_argument for bad options
slam2d::Pose2 patchMotion(const Eigen::Isometry2d& reference_from_query_px, const PatchOptions& options);

}  // namespace rmap::loop
