#pragma once
/// @file cuboid.h
/// Cuboids: the stored form of a fused block, and the world-frame form that
/// queries return.

#include <cstdint>

#include "map3d/cell_key.h"

namespace rmap::map3d {

/// An axis-aligned cuboid of cells inside one block, 8 bytes: inclusive
/// in-block corners packed 4 bits per axis, and one log-odds value.
struct PackedCuboid {
  uint16_t lo_packed = 0;  ///< x | y << 4 | z << 8 of the lowest cell
  uint16_t hi_packed = 0;  ///< x | y << 4 | z << 8 of the highest cell (inclusive)
  float log_odds = 0.0f;

  static uint16_t pack(int x, int y, int z) { return static_cast<uint16_t>(x | (y << 4) | (z << 8)); }
  int lo(int axis) const { return (lo_packed >> (4 * axis)) & 15; }
  int hi(int axis) const { return (hi_packed >> (4 * axis)) & 15; }
  int cellCount() const { return (hi(0) - lo(0) + 1) * (hi(1) - lo(1) + 1) * (hi(2) - lo(2) + 1); }
  bool contains(int x, int y, int z) const {
    return x >= lo(0) && x <= hi(0) && y >= lo(1) && y <= hi(1) && z >= lo(2) && z <= hi(2);
  }
};
static_assert(sizeof(PackedCuboid) == 8);

/// A cuboid in base-cell indices of the whole map, as queries return it.
struct CuboidBox {
  CellKey min;            ///< lowest cell (inclusive)
  CellKey max;            ///< highest cell (inclusive)
  float log_odds = 0.0f;  ///< value shared by its cells (for coarse levels: the max)
};

}  // namespace rmap::map3d
