#pragma once
/// @file fusion.h
/// Decomposition of a block into maximal cuboids of similar occupancy, and
/// the reverse expansion.

#include <vector>

#include "map3d/cuboid.h"
#include "map3d/dense_cells.h"

namespace rmap::map3d {

/// Greedy decomposition of the known cells of a block into disjoint cuboids:
/// grows each cuboid from its lowest free cell along x, then y, then z while
/// every added cell is known, not yet taken, on the same side of
/// `occupied_threshold` and keeps the cuboid's log-odds span within
/// `tolerance`. Each cuboid stores the middle of its span.
/// @param tolerance  log-odds; 0 merges only equal values
std::vector<PackedCuboid> fuseBlock(const DenseCells& cells, float tolerance, float occupied_threshold);

/// Writes the cuboids' values into `cells` (known bits set); other cells untouched.
void expandCuboids(const std::vector<PackedCuboid>& cuboids, DenseCells& cells);

/// Index of the cuboid that holds in-block cell (x, y, z), or -1.
int findCuboid(const std::vector<PackedCuboid>& cuboids, int x, int y, int z);

}  // namespace rmap::map3d
