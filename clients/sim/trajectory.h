#pragma once
/// @file trajectory.h
/// Sensor trajectories through the navigable space of a world: the ground
/// truth poses from which simulated scans are taken.

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "sim/navigable.h"
#include "sim/voxel_world.h"

namespace rmap::sim {

/// The NavigableOptions fields (sensor height, clearance, body, step, cell)
/// define where the carrier may be; the rest shape the tour.
struct TrajectoryOptions : NavigableOptions {
  int num_poses = 200;            ///< ≥ 1
  double step_m = 0.3;            ///< metres between consecutive sensor positions (3D), ≥ max_step_m + 0.01
  double coverage_radius_m = 2.0; ///< metres, ≥ 0: a pose marks the standing places this close as visited

  /// @throws std::invalid_argument naming the first bad parameter
  void validate() const;
};

/// Plans a tour of `num_poses` sensor poses through the largest connected
/// part of the world's navigable space (see NavigableSpace):
///  - it starts at a random standing place and repeatedly travels, on the
///    shortest path of the 8-connected grid (straightened where the straight
///    line stays navigable), to the place farthest by path length from every
///    place visited so far (farthest-point sampling), so far-apart parts come
///    first and rooms get entered; places within coverage_radius_m of a pose
///    count as visited; once all are, the marks are cleared and the tour goes on;
///  - sensor positions follow that path at most step_m apart (10 µm less on
///    plain stretches, less where the path steps up or down), at
///    sensor_height_m above the standing surface, each
///    inside a navigable cell, so each keeps clearance_m from occupied voxels
///    (and lies in known free space when the world has some); the path may
///    climb stairs whose steps are at most max_step_m high;
///  - the sensor is level (roll = pitch = 0) with its x axis along the
///    horizontal direction of travel (the previous one when the next move is
///    purely vertical, and for the last pose).
/// Deterministic for a given world, options and seed.
/// @throws std::invalid_argument for bad options
/// @throws std::runtime_error when the world has fewer than two connected
///         navigable places (message says what the carrier needs)
std::vector<Eigen::Isometry3d> planTrajectory(const VoxelWorld& world, const TrajectoryOptions& options,
                                              uint64_t seed);

}  // namespace rmap::sim
