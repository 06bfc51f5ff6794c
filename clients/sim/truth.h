#pragma once
/// @file truth.h
/// Ground truth for scoring maps against the simulated world.

#include <Eigen/Core>

#include "sim/voxel_world.h"

namespace rmap::sim {

/// True state of a map base cell: the state of the world voxel containing
/// its centre (outside the world grid: free). Exact cell-for-cell when the map
/// resolution equals the world's voxel_m, since both use floor(coord/res)
/// (VoxelWorld, map3d::Grid); for coarser map cells it samples the voxel at
/// the centre only, so thin surfaces off-centre read as free.
inline bool trueOccupied(const VoxelWorld& world, const Eigen::Vector3d& cell_center_m) {
  return world.occupied(cell_center_m);
}

}  // namespace rmap::sim
