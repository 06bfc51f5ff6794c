#pragma once
/// @file loop_course.h
/// A procedural ring corridor for place-recognition tests: a closed corridor
/// of constant width around a central block, so a carrier can drive the same
/// loop again and again and revisit every place with the same heading.
///
/// Frame: the outer footprint is [0, size_x_m] × [0, size_y_m], the floor top
/// is z = 0, the ceiling underside z = height_m. Walls are wall_m thick.
/// Every place must look different, as real places do, so surfaces carry
/// texture in their reflectivity (which both the camera renderer and the lidar
/// intensities see):
///  - walls: base 0.40–0.60 and posters (rectangles one voxel deep on the
///    corridor face, 0.2–1.4 m wide and tall, ρ uniform in 0.05–0.95,
///    posters_per_m per metre of wall on average);
///  - floor: 0.5 m tiles of ρ 0.10–0.45; ceiling 0.60–0.80;
///  - cabinets: boxes against the walls (0.4–1.2 m long, 0.3–0.6 m deep,
///    0.5–2.0 m tall, ρ 0.05–0.90), cabinets_per_m per metre of wall, never in
///    the corner squares, so the middle 1.6 m of the corridor stays free;
///  - every surface voxel's ρ varies by ±voxel_noise (uniform, clamped to [0, 1]).

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "sim/voxel_world.h"

namespace rmap::sim {

struct LoopCourseOptions {
  double size_x_m = 20.0;         ///< footprint, metres, ≥ 2·corridor_width_m + 2
  double size_y_m = 12.0;         ///< footprint, metres, ≥ 2·corridor_width_m + 2
  double corridor_width_m = 3.0;  ///< free width between the walls, metres, ≥ 2.8 (room for cabinets and a 1.6 m lane)
  double height_m = 3.0;          ///< floor to ceiling, metres, [2, 10]
  double wall_m = 0.1;            ///< wall, floor and ceiling thickness, metres, ≥ voxel_m
  double posters_per_m = 1.5;     ///< ≥ 0
  double cabinets_per_m = 0.2;    ///< ≥ 0
  double voxel_noise = 0.06;      ///< [0, 0.5]
  double voxel_m = 0.05;          ///< metres, (0, 0.2]

  /// @throws std::invalid_argument naming the first bad parameter
  void validate() const;
};

struct LoopCourse {
  VoxelWorld world;
  /// Corridor centre line, a closed counter-clockwise rectangle (4 corners,
  /// metres, z = 0); the corridor is free for ±0.8 m around it.
  std::vector<Eigen::Vector2d> centerline_m;
};

/// Builds the course; the same options and seed give the same world.
/// @throws std::invalid_argument for bad options
LoopCourse makeLoopCourse(const LoopCourseOptions& options, uint64_t seed);

}  // namespace rmap::sim
