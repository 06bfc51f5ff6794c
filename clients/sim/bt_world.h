#pragma once
/// @file bt_world.h
/// A simulated world made from an OctoMap tree (e.g. geb079.bt): real
/// building geometry for the simulated sensors.

#include <cstdint>

#include "map3d/octomap_bt.h"
#include "sim/voxel_world.h"

namespace rmap::sim {

/// Builds a world whose voxels are the tree's base cells: voxel_m =
/// tree.resolution_m and world voxel i is tree cell i (both floor(coord/res)).
/// Occupied leaves of size s fill s³ occupied voxels; free leaves become
/// known free space (VoxelWorld::knownFree), unknown space is free but not
/// known free. The grid spans the bounding box of all leaves.
///
/// The tree has no reflectivity, so a plausible one is synthesised: a smooth
/// random field with metre-scale patches (materials, paint, furniture),
///   ρ(p) = clamp(ρ₀ · (1 + 0.6·n(p)), 0.02, 1),
///   n(p) = 0.7·N(p / 2 m) + 0.3·N(p / 0.5 m),
/// where N is trilinear value noise in [−1, 1] on the integer lattice, its
/// lattice values hashed from `seed`. The same seed gives the same world.
///
/// @param reflectivity_default  ρ₀, in (0, 1]
/// @throws std::invalid_argument for a non-positive resolution, a tree
///         without occupied leaves, a bad ρ₀, or a bounding box beyond
///         VoxelWorld::kMaxVoxels
VoxelWorld worldFromBt(const map3d::BtTree& tree, float reflectivity_default, uint64_t seed);

}  // namespace rmap::sim
