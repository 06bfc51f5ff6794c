#pragma once
/// @file voxel_world.h
/// Dense-in-effect voxel grid that simulated worlds are made of: occupancy,
/// surface reflectivity and (for worlds imported from a map) known free space.
///
/// Voxels sit on a global lattice: voxel g spans [g·voxel_m, (g+1)·voxel_m)
/// per axis and a point's voxel is `floor(coord * (1/voxel_m))`, the same
/// arithmetic as map3d::Grid, so with voxel_m equal to the map resolution a
/// world voxel and a map base cell are the same cube. The grid covers global
/// voxels [min_voxel, min_voxel + dims); everything outside it is free.
///
/// Storage is sparse by 8³ bricks: a brick is allocated the first time one of
/// its voxels is set, so empty space costs 4 bytes per brick, and the ray
/// caster skips unallocated or emptied bricks in one step.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

namespace rmap::sim {

/// Inclusive range of global voxel indices.
using VoxelBox = Eigen::AlignedBox<int, 3>;

/// The box from corner (x0, y0, z0) to corner (x1, y1, z1), metres; the worlds are built of these.
inline Eigen::AlignedBox3d box(double x0, double y0, double z0, double x1, double y1, double z1) {
  return {Eigen::Vector3d(x0, y0, z0), Eigen::Vector3d(x1, y1, z1)};
}

/// First occupied voxel along a ray.
struct RayHit {
  double range_m = 0.0;    ///< distance from the ray origin to point_m
  Eigen::Vector3d point_m; ///< where the ray enters the voxel (on its face)
  Eigen::Vector3d normal;  ///< unit normal of the entered face, pointing against the ray
  float reflectivity = 0;  ///< surface reflectivity of the hit voxel, [0, 1]
};

class VoxelWorld {
 public:
  /// Most voxels a grid may span (16 Gi: 128 MiB of brick index).
  static constexpr int64_t kMaxVoxels = int64_t{1} << 34;

  /// @param voxel_m    voxel edge in metres, > 0
  /// @param min_voxel  global index of the lowest voxel of the grid
  /// @param dims       voxels per axis, each ≥ 1, product ≤ kMaxVoxels, and
  ///                   min_voxel + dims must not overflow int32
  /// @throws std::invalid_argument otherwise
  VoxelWorld(double voxel_m, const Eigen::Vector3i& min_voxel, const Eigen::Vector3i& dims);

  /// The smallest grid whose voxels cover a box.
  /// @param bounds_m  non-empty box, metres
  /// @throws std::invalid_argument for an empty box or bad voxel size/extent
  static VoxelWorld covering(const Eigen::AlignedBox3d& bounds_m, double voxel_m);

  double voxelSize() const { return voxel_m_; }
  const Eigen::Vector3i& minVoxel() const { return min_voxel_; }
  const Eigen::Vector3i& dims() const { return dims_; }
  /// Inclusive global index range of the grid.
  VoxelBox voxelBounds() const { return {min_voxel_, min_voxel_ + dims_ - Eigen::Vector3i::Ones()}; }
  /// Metric extent of the grid: [min_voxel·v, (min_voxel + dims)·v].
  Eigen::AlignedBox3d bounds() const;

  /// Global voxel index of a point; false when the point is outside the grid or not finite.
  bool voxelOf(const Eigen::Vector3d& p_m, Eigen::Vector3i& voxel) const;
  Eigen::Vector3d voxelCenter(const Eigen::Vector3i& voxel) const {
    return (voxel.cast<double>() + Eigen::Vector3d::Constant(0.5)) * voxel_m_;
  }
  bool contains(const Eigen::Vector3i& voxel) const {
    return (voxel.array() >= min_voxel_.array()).all() && ((voxel - min_voxel_).array() < dims_.array()).all();
  }

  /// Voxels whose centres lie in a closed box. A box whose faces lie on voxel
  /// faces fills exactly the voxels inside it; a box thinner than a voxel can
  /// select none. Parts outside the grid are ignored.
  VoxelBox voxelsInBox(const Eigen::AlignedBox3d& box_m) const;

  /// Marks the voxels of voxelsInBox(box_m) occupied with a reflectivity.
  /// @param reflectivity  [0, 1], stored quantised to 1/255
  /// @throws std::invalid_argument for a reflectivity outside [0, 1]
  void fillBox(const Eigen::AlignedBox3d& box_m, float reflectivity);
  /// Marks the voxels of voxelsInBox(box_m) free.
  void clearBox(const Eigen::AlignedBox3d& box_m);
  /// As fillBox/clearBox, on an inclusive global index range (clipped to the grid).
  void fillVoxels(const VoxelBox& voxels, float reflectivity);
  void clearVoxels(const VoxelBox& voxels);

  /// Occupancy of the voxel containing a point; outside the grid: free.
  bool occupied(const Eigen::Vector3d& p_m) const;
  bool occupiedVoxel(const Eigen::Vector3i& voxel) const;
  /// Reflectivity of the voxel containing a point, 0 when it is free or outside.
  float reflectivityAt(const Eigen::Vector3d& p_m) const;
  float reflectivityVoxel(const Eigen::Vector3i& voxel) const;

  /// Known free space: voxels a map observed as free. Worlds built from
  /// geometry alone have none (hasKnownFree() false); trajectories through
  /// map-derived worlds must stay inside it because only there the world is
  /// known to be empty.
  void markKnownFree(const VoxelBox& voxels);
  bool hasKnownFree() const { return !free_index_.empty(); }
  bool knownFree(const Eigen::Vector3d& p_m) const;
  bool knownFreeVoxel(const Eigen::Vector3i& voxel) const;
  size_t knownFreeCount() const;

  size_t occupiedCount() const { return occupied_count_; }
  /// Heap bytes of the storage (brick indices and brick payloads).
  size_t memoryBytes() const;

  /// Casts a ray through the grid with an exact 3D DDA (Amanatides & Woo),
  /// skipping empty 8³ bricks.
  /// @param origin_m   ray origin in metres; may lie outside the grid
  /// @param unit_dir   direction, unit length (|‖d‖² − 1| ≤ 1e-6)
  /// @param max_range_m  metres, > 0; only hits at range < max_range_m count
  /// @return the entry point into the first occupied voxel, or nothing. An
  ///         origin inside an occupied voxel is a hit at range 0 whose normal
  ///         is −unit_dir (no face was crossed).
  /// @throws std::invalid_argument for a non-finite origin, a non-unit
  ///         direction or a non-positive/NaN range
  std::optional<RayHit> castRay(const Eigen::Vector3d& origin_m, const Eigen::Vector3d& unit_dir,
                                double max_range_m) const;

  /// Calls f(const Eigen::Vector3i& voxel) for every occupied voxel, brick by brick.
  template <class F>
  void forEachOccupiedVoxel(F&& f) const;

 private:
  static constexpr int kBrickShift = 3;
  static constexpr int kBrickEdge = 1 << kBrickShift;
  static constexpr int kBrickVoxels = kBrickEdge * kBrickEdge * kBrickEdge;

  /// Occupancy bits: word z holds the 8×8 slice at in-brick z, bit y·8+x.
  using BrickBits = std::array<uint64_t, kBrickEdge>;
  struct OccupiedBrick {
    BrickBits bits{};
    std::array<uint8_t, kBrickVoxels> reflectivity{};  ///< ρ·255, index (z·8+y)·8+x
    uint16_t count = 0;                                 ///< occupied voxels
  };

  struct LocalVoxel {
    int64_t brick;  ///< linear brick index
    int bit_word;   ///< in-brick z
    int bit;        ///< in-brick y·8+x
  };

  int64_t brickLinear(int bx, int by, int bz) const {
    return (static_cast<int64_t>(bz) * brick_dims_.y() + by) * brick_dims_.x() + bx;
  }
  /// In-grid voxel (local index l = global − min_voxel) to brick position.
  LocalVoxel local(const Eigen::Vector3i& l) const {
    return {brickLinear(l.x() >> kBrickShift, l.y() >> kBrickShift, l.z() >> kBrickShift),
            l.z() & (kBrickEdge - 1), ((l.y() & (kBrickEdge - 1)) << kBrickShift) | (l.x() & (kBrickEdge - 1))};
  }
  /// Clips a global range to the grid and returns it in local indices; false if empty.
  bool clipLocal(const VoxelBox& voxels, Eigen::Vector3i& lo, Eigen::Vector3i& hi) const;
  /// Calls f(brick linear index, in-brick z, 64-bit slice mask) over a local range.
  template <class F>
  void forEachSliceMask(const Eigen::Vector3i& lo, const Eigen::Vector3i& hi, F&& f) const;

  double voxel_m_;
  double inv_voxel_;
  Eigen::Vector3i min_voxel_;
  Eigen::Vector3i dims_;
  Eigen::Vector3i brick_dims_;
  std::vector<int32_t> occ_index_;  ///< per brick: index into occ_pool_, −1 if never set
  std::vector<OccupiedBrick> occ_pool_;
  std::vector<int32_t> free_index_;  ///< as occ_index_ for known free; empty until first marked
  std::vector<BrickBits> free_pool_;
  size_t occupied_count_ = 0;
};

template <class F>
void VoxelWorld::forEachOccupiedVoxel(F&& f) const {
  for (int bz = 0; bz < brick_dims_.z(); ++bz) {
    for (int by = 0; by < brick_dims_.y(); ++by) {
      for (int bx = 0; bx < brick_dims_.x(); ++bx) {
        const int32_t index = occ_index_[brickLinear(bx, by, bz)];
        if (index < 0 || occ_pool_[index].count == 0) continue;
        const BrickBits& bits = occ_pool_[index].bits;
        const Eigen::Vector3i base = min_voxel_ + Eigen::Vector3i(bx, by, bz) * kBrickEdge;
        for (int z = 0; z < kBrickEdge; ++z) {
          for (uint64_t word = bits[z]; word != 0; word &= word - 1) {
            const int bit = std::countr_zero(word);
            f(Eigen::Vector3i(base.x() + (bit & (kBrickEdge - 1)), base.y() + (bit >> kBrickShift), base.z() + z));
          }
        }
      }
    }
  }
}

}  // namespace rmap::sim
