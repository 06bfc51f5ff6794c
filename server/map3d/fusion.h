#pragma once
/// @file fusion.h
/// Decomposition of a block into maximal cuboids of similar occupancy, and
/// the reverse expansion.

#include <array>
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

/// Index of the cuboid that holds in-block cell (x, y, z), or -1 (a linear scan).
int findCuboid(const std::vector<PackedCuboid>& cuboids, int x, int y, int z);

/// Lists, per z slice of a block, the cuboids that reach into it, so a point
/// lookup scans about a sixteenth of a block's cuboids times their depth.
struct SliceIndex {
  static constexpr size_t kMinCuboids = 32;  ///< smaller blocks scan linearly
  std::array<uint32_t, kBlockEdge + 1> offsets{};  ///< slice z lists cuboids[offsets[z], offsets[z+1])
  std::vector<uint16_t> cuboids;                   ///< cuboid indices, slice after slice

  explicit SliceIndex(const std::vector<PackedCuboid>& fused);
  int find(const std::vector<PackedCuboid>& fused, int x, int y, int z) const;
  size_t memoryBytes() const { return sizeof(*this) + cuboids.capacity() * sizeof(uint16_t); }
};

}  // namespace rmap::map3d
