#pragma once
/// @file cell_key.h
/// Integer addressing of base cells and blocks of the cuboid map.
///
/// A base cell is the cube [i·res, (i+1)·res) per axis; its index follows
/// OctoMap's discretisation exactly (`floor(coord / res)` computed as
/// `floor(coord * (1/res))` in double), so both maps put every point into the
/// same cell and results are comparable cell for cell.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <functional>

namespace rmap::map3d {

/// Edge length of a block, in base cells. Blocks are the unit of storage,
/// locking-free scratch and fusion; 16 keeps in-block coordinates in 4 bits.
inline constexpr int kBlockEdge = 16;
inline constexpr int kBlockShift = 4;
inline constexpr int kBlockCells = kBlockEdge * kBlockEdge * kBlockEdge;

/// Cells addressable per axis are [-kCellLimit, kCellLimit), the range of
/// OctoMap's 16-level tree, so every map can be exported to `.bt`.
inline constexpr int32_t kCellLimit = 32768;

/// Index of a base cell.
struct CellKey {
  int32_t x = 0, y = 0, z = 0;
  friend bool operator==(const CellKey&, const CellKey&) = default;
  int32_t operator[](int axis) const { return axis == 0 ? x : (axis == 1 ? y : z); }
  int32_t& operator[](int axis) { return axis == 0 ? x : (axis == 1 ? y : z); }
};

/// Index of a block: the cell index shifted right by kBlockShift.
struct BlockKey {
  int32_t x = 0, y = 0, z = 0;
  friend bool operator==(const BlockKey&, const BlockKey&) = default;
};

struct BlockKeyHash {
  size_t operator()(const BlockKey& k) const noexcept {
    // Large primes spread neighbouring blocks across buckets (Teschner et al.).
    return (static_cast<size_t>(static_cast<uint32_t>(k.x)) * 73856093u) ^
           (static_cast<size_t>(static_cast<uint32_t>(k.y)) * 19349669u) ^
           (static_cast<size_t>(static_cast<uint32_t>(k.z)) * 83492791u);
  }
};

inline BlockKey blockOf(const CellKey& c) {
  return {c.x >> kBlockShift, c.y >> kBlockShift, c.z >> kBlockShift};
}

/// Linear index of a cell inside its block, x fastest.
inline int localIndex(const CellKey& c) {
  constexpr int m = kBlockEdge - 1;
  return ((c.z & m) << (2 * kBlockShift)) | ((c.y & m) << kBlockShift) | (c.x & m);
}

inline int localIndex(int lx, int ly, int lz) {
  return (lz << (2 * kBlockShift)) | (ly << kBlockShift) | lx;
}

inline CellKey cellOf(const BlockKey& b, int local_index) {
  constexpr int m = kBlockEdge - 1;
  return {(b.x << kBlockShift) | (local_index & m),
          (b.y << kBlockShift) | ((local_index >> kBlockShift) & m),
          (b.z << kBlockShift) | (local_index >> (2 * kBlockShift))};
}

inline bool cellInRange(const CellKey& c) {
  return c.x >= -kCellLimit && c.x < kCellLimit && c.y >= -kCellLimit && c.y < kCellLimit &&
         c.z >= -kCellLimit && c.z < kCellLimit;
}

/// Discretisation shared by every component (map, simulator truth, benchmarks).
class Grid {
 public:
  /// @param resolution_m  edge of a base cell in metres, > 0
  explicit Grid(double resolution_m) : resolution_m_(resolution_m), inv_resolution_(1.0 / resolution_m) {}

  double resolution() const { return resolution_m_; }

  /// Cell index of one coordinate; same arithmetic as OctoMap's coordToKey.
  /// Coordinates outside the addressable range are clamped to its edge cells
  /// (NaN gives the lowest cell).
  int32_t index(double coord_m) const {
    const double scaled = std::floor(inv_resolution_ * coord_m);
    return scaled >= kCellLimit ? kCellLimit - 1 : scaled >= -kCellLimit ? static_cast<int32_t>(scaled) : -kCellLimit;
  }

  /// False for NaN/inf or coordinates outside the addressable range. Float
  /// points are widened to double first, so a double query of the same
  /// coordinate lands in the same cell.
  template <class Scalar>
  bool cellChecked(const Eigen::Matrix<Scalar, 3, 1>& p, CellKey& out) const {
    for (int a = 0; a < 3; ++a) {
      const double scaled = inv_resolution_ * static_cast<double>(p[a]);
      if (!(scaled >= -kCellLimit && scaled < kCellLimit)) return false;  // also rejects NaN
      // floor(scaled) in range, without a libm call (the baseline x86-64 ISA
      // has no rounding instruction): truncate, step down below zero
      const int32_t truncated = static_cast<int32_t>(scaled);
      out[a] = truncated - (scaled < truncated ? 1 : 0);
    }
    return true;
  }

  /// Centre of a cell along one axis, in metres (OctoMap's keyToCoord).
  double center(int32_t index) const { return (static_cast<double>(index) + 0.5) * resolution_m_; }
  Eigen::Vector3d center(const CellKey& c) const { return {center(c.x), center(c.y), center(c.z)}; }

 private:
  double resolution_m_;
  double inv_resolution_;
};

}  // namespace rmap::map3d

template <>
struct std::hash<rmap::map3d::BlockKey> : rmap::map3d::BlockKeyHash {};
