#pragma once
/// @file building.h
/// Procedurally generated office-like building as a VoxelWorld.
///
/// Frame: the outer footprint is [0, size_x_m] × [0, size_y_m]; the top of the
/// ground-floor slab is z = 0, storey f stands at z = f·floor_height_m. Every
/// storey has the same plan: a corridor along x through the middle, rooms on
/// both sides (partitions between them, a door from each room to the
/// corridor, sometimes a door between neighbouring rooms), furniture in the
/// rooms. With two or more storeys a stair hall at the west end holds
/// switchback flights (solid concrete steps, an opening in the slab above each
/// flight with a railing); the hall is open to the corridor. A roof slab
/// closes the top storey; there are no windows, so every ray from inside hits.
/// Reflectivity ranges (uniform, drawn per surface): floors 0.10–0.35,
/// corridor floor 0.20–0.40, ceilings 0.60–0.80, outer walls 0.35–0.60,
/// partitions 0.45–0.80, stairs 0.25–0.45, railings 0.60–0.90, furniture
/// 0.05–0.90, retro-reflective tape markers on the corridor walls 0.90–1.00.
///
/// The navigable floor space is given by NavigableSpace (navigable.h) on the
/// returned world; the layout below records what was built, for tests and demos.

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "sim/voxel_world.h"

namespace rmap::sim {

struct BuildingOptions {
  double size_x_m = 24.0;            ///< footprint along the corridor, metres
  double size_y_m = 16.0;            ///< footprint across the corridor, metres
  int floors = 1;                    ///< storeys, [1, 10]
  double floor_height_m = 3.0;       ///< slab top to slab top, metres, ≥ door_height_m + slab_thickness_m + 0.3
  double slab_thickness_m = 0.2;     ///< floor/ceiling slabs and roof, metres, [voxel_m, 1]
  double outer_wall_m = 0.25;        ///< metres, ≥ voxel_m
  double inner_wall_m = 0.1;         ///< partitions and corridor walls, metres, ≥ voxel_m
  double corridor_width_m = 2.0;     ///< metres, ≥ 1.2
  int min_rooms = 4;                 ///< rooms per storey (both sides together), ≥ 2
  int max_rooms = 8;                 ///< ≥ min_rooms; fewer are built if they would be narrower than min_room_width_m
  double min_room_width_m = 2.5;     ///< along the corridor, metres, ≥ door_width_m + 0.6; also the least room depth
  double door_width_m = 1.0;         ///< metres, ≥ 0.6
  double door_height_m = 2.1;        ///< metres, ≥ 1.8
  double stair_width_m = 1.2;        ///< flight width, metres, ≥ 0.8 (used when floors ≥ 2)
  int max_furniture_per_room = 4;    ///< ≥ 0; each room gets a uniform count in [0, max]
  double voxel_m = 0.025;            ///< metres, (0, 0.5]

  /// @throws std::invalid_argument naming the first bad or inconsistent parameter
  void validate() const;
};

/// What makeBuilding built, in metres (world frame).
struct BuildingLayout {
  std::vector<Eigen::AlignedBox3d> rooms;          ///< free interior of each room (floor to ceiling)
  std::vector<Eigen::AlignedBox3d> corridors;      ///< free interior of each storey's corridor, stair hall excluded
  std::vector<Eigen::AlignedBox3d> stair_halls;    ///< free interior of each storey's stair hall
  std::vector<Eigen::AlignedBox3d> walls;          ///< interior walls, before door openings were cut
  std::vector<Eigen::AlignedBox3d> doors;          ///< door openings: empty boxes through their wall
  std::vector<Eigen::AlignedBox3d> stair_flights;  ///< bounding box of each flight (from storey f to f + 1)
  std::vector<Eigen::AlignedBox3d> furniture;      ///< bounding box of each piece
  std::vector<Eigen::AlignedBox3d> markers;        ///< high-reflectivity tape strips (one voxel deep)
  double step_rise_m = 0.0;                        ///< stair step height (0 without stairs)
  double step_tread_m = 0.0;                       ///< stair step depth (0 without stairs)
};

/// Generates a building; the same options and seed give the same world.
/// @param layout  optional; receives what was built
/// @throws std::invalid_argument for bad options
VoxelWorld makeBuilding(const BuildingOptions& options, uint64_t seed, BuildingLayout* layout = nullptr);

}  // namespace rmap::sim
