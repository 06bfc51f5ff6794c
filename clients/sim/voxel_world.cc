#include "sim/voxel_world.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rmap::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

uint8_t quantiseReflectivity(float reflectivity) {
  if (!(reflectivity >= 0.0f && reflectivity <= 1.0f)) {
    throw std::invalid_argument("VoxelWorld: reflectivity must be in [0, 1], got " + std::to_string(reflectivity));
  }
  return static_cast<uint8_t>(std::lround(reflectivity * 255.0f));
}

/// Mask of the in-slice bits x ∈ [x0, x1], y ∈ [y0, y1] (bit y·8+x).
uint64_t sliceMask(int x0, int x1, int y0, int y1) {
  const uint64_t row = (0xFFu >> (7 - (x1 - x0))) << x0;
  uint64_t mask = 0;
  for (int y = y0; y <= y1; ++y) mask |= row << (8 * y);
  return mask;
}

}  // namespace

VoxelWorld::VoxelWorld(double voxel_m, const Eigen::Vector3i& min_voxel, const Eigen::Vector3i& dims)
    : voxel_m_(voxel_m), inv_voxel_(1.0 / voxel_m), min_voxel_(min_voxel), dims_(dims) {
  if (!(voxel_m > 0.0) || !std::isfinite(voxel_m)) {
    throw std::invalid_argument("VoxelWorld: voxel_m must be a positive finite size, got " + std::to_string(voxel_m));
  }
  int64_t total = 1;
  for (int a = 0; a < 3; ++a) {
    if (dims[a] < 1) throw std::invalid_argument("VoxelWorld: every dimension must be ≥ 1 voxel");
    if (static_cast<int64_t>(min_voxel[a]) + dims[a] > std::numeric_limits<int32_t>::max()) {
      throw std::invalid_argument("VoxelWorld: min_voxel + dims overflows the int32 voxel index");
    }
    total *= dims[a];
    if (total > kMaxVoxels) {
      throw std::invalid_argument("VoxelWorld: grid of more than 2^34 voxels requested; use a larger voxel_m");
    }
  }
  brick_dims_ = (dims_.array() + (kBrickEdge - 1)) / kBrickEdge;
  occ_index_.assign(static_cast<size_t>(brick_dims_.cast<int64_t>().prod()), -1);
}

VoxelWorld VoxelWorld::covering(const Eigen::AlignedBox3d& bounds_m, double voxel_m) {
  if (bounds_m.isEmpty() || !bounds_m.min().allFinite() || !bounds_m.max().allFinite()) {
    throw std::invalid_argument("VoxelWorld::covering: bounds must be a finite non-empty box");
  }
  if (!(voxel_m > 0.0) || !std::isfinite(voxel_m)) {
    throw std::invalid_argument("VoxelWorld::covering: voxel_m must be positive, got " + std::to_string(voxel_m));
  }
  const double inv = 1.0 / voxel_m;
  Eigen::Vector3i lo, dims;
  for (int a = 0; a < 3; ++a) {
    const double first = std::floor(bounds_m.min()[a] * inv);
    // A max face on a voxel face needs no voxel above it; otherwise the voxel containing it.
    const double last = std::max(first, std::ceil(bounds_m.max()[a] * inv) - 1.0);
    if (first < std::numeric_limits<int32_t>::min() || last > std::numeric_limits<int32_t>::max() / 2) {
      throw std::invalid_argument("VoxelWorld::covering: bounds too far from the origin for this voxel size");
    }
    lo[a] = static_cast<int>(first);
    dims[a] = static_cast<int>(last - first) + 1;
  }
  return VoxelWorld(voxel_m, lo, dims);
}

Eigen::AlignedBox3d VoxelWorld::bounds() const {
  return {min_voxel_.cast<double>() * voxel_m_, (min_voxel_ + dims_).cast<double>() * voxel_m_};
}

bool VoxelWorld::voxelOf(const Eigen::Vector3d& p_m, Eigen::Vector3i& voxel) const {
  for (int a = 0; a < 3; ++a) {
    // Same arithmetic as map3d::Grid::index; the comparison also rejects NaN.
    const double local = std::floor(inv_voxel_ * p_m[a]) - min_voxel_[a];
    if (!(local >= 0.0 && local < dims_[a])) return false;
    voxel[a] = min_voxel_[a] + static_cast<int>(local);
  }
  return true;
}

VoxelBox VoxelWorld::voxelsInBox(const Eigen::AlignedBox3d& box_m) const {
  VoxelBox out;  // empty by default
  if (box_m.isEmpty()) return out;
  const VoxelBox grid = voxelBounds();
  Eigen::Vector3i lo, hi;
  for (int a = 0; a < 3; ++a) {
    // Centre (g + ½)·v ∈ [min, max]  ⇔  g ∈ [min/v − ½, max/v − ½]; clamp before the int cast.
    const double first = std::ceil(box_m.min()[a] * inv_voxel_ - 0.5);
    const double last = std::floor(box_m.max()[a] * inv_voxel_ - 0.5);
    if (!(first <= last)) return out;
    lo[a] = static_cast<int>(std::clamp<double>(first, grid.min()[a] - 1.0, grid.max()[a] + 1.0));
    hi[a] = static_cast<int>(std::clamp<double>(last, grid.min()[a] - 1.0, grid.max()[a] + 1.0));
  }
  return VoxelBox(lo, hi).intersection(grid);
}

bool VoxelWorld::clipLocal(const VoxelBox& voxels, Eigen::Vector3i& lo, Eigen::Vector3i& hi) const {
  const VoxelBox clipped = voxels.intersection(voxelBounds());
  if (clipped.isEmpty()) return false;
  lo = clipped.min() - min_voxel_;
  hi = clipped.max() - min_voxel_;
  return true;
}

template <class F>
void VoxelWorld::forEachSliceMask(const Eigen::Vector3i& lo, const Eigen::Vector3i& hi, F&& f) const {
  constexpr int m = kBrickEdge - 1;
  for (int bz = lo.z() >> kBrickShift; bz <= hi.z() >> kBrickShift; ++bz) {
    for (int by = lo.y() >> kBrickShift; by <= hi.y() >> kBrickShift; ++by) {
      for (int bx = lo.x() >> kBrickShift; bx <= hi.x() >> kBrickShift; ++bx) {
        const int x0 = std::max(lo.x() - bx * kBrickEdge, 0), x1 = std::min(hi.x() - bx * kBrickEdge, m);
        const int y0 = std::max(lo.y() - by * kBrickEdge, 0), y1 = std::min(hi.y() - by * kBrickEdge, m);
        const int z0 = std::max(lo.z() - bz * kBrickEdge, 0), z1 = std::min(hi.z() - bz * kBrickEdge, m);
        const uint64_t mask = sliceMask(x0, x1, y0, y1);
        const int64_t brick = brickLinear(bx, by, bz);
        for (int z = z0; z <= z1; ++z) f(brick, z, mask);
      }
    }
  }
}

void VoxelWorld::fillBox(const Eigen::AlignedBox3d& box_m, float reflectivity) {
  fillVoxels(voxelsInBox(box_m), reflectivity);
}

void VoxelWorld::clearBox(const Eigen::AlignedBox3d& box_m) { clearVoxels(voxelsInBox(box_m)); }

void VoxelWorld::fillVoxels(const VoxelBox& voxels, float reflectivity) {
  const uint8_t q = quantiseReflectivity(reflectivity);
  Eigen::Vector3i lo, hi;
  if (!clipLocal(voxels, lo, hi)) return;
  forEachSliceMask(lo, hi, [&](int64_t brick, int z, uint64_t mask) {
    int32_t& index = occ_index_[brick];
    if (index < 0) {
      index = static_cast<int32_t>(occ_pool_.size());
      occ_pool_.emplace_back();
    }
    OccupiedBrick& b = occ_pool_[index];
    const int added = std::popcount(mask & ~b.bits[z]);
    b.bits[z] |= mask;
    b.count = static_cast<uint16_t>(b.count + added);
    occupied_count_ += added;
    for (uint64_t m = mask; m != 0; m &= m - 1) b.reflectivity[(z << 6) | std::countr_zero(m)] = q;
  });
}

void VoxelWorld::clearVoxels(const VoxelBox& voxels) {
  Eigen::Vector3i lo, hi;
  if (!clipLocal(voxels, lo, hi)) return;
  // Emptied bricks stay allocated (count 0): the ray caster skips them as cheaply as absent ones.
  forEachSliceMask(lo, hi, [&](int64_t brick, int z, uint64_t mask) {
    const int32_t index = occ_index_[brick];
    if (index < 0) return;
    OccupiedBrick& b = occ_pool_[index];
    const int removed = std::popcount(mask & b.bits[z]);
    b.bits[z] &= ~mask;
    b.count = static_cast<uint16_t>(b.count - removed);
    occupied_count_ -= removed;
  });
}

bool VoxelWorld::occupiedVoxel(const Eigen::Vector3i& voxel) const {
  if (!contains(voxel)) return false;
  const LocalVoxel l = local(voxel - min_voxel_);
  const int32_t index = occ_index_[l.brick];
  return index >= 0 && ((occ_pool_[index].bits[l.bit_word] >> l.bit) & 1u);
}

bool VoxelWorld::occupied(const Eigen::Vector3d& p_m) const {
  Eigen::Vector3i v;
  return voxelOf(p_m, v) && occupiedVoxel(v);
}

float VoxelWorld::reflectivityVoxel(const Eigen::Vector3i& voxel) const {
  if (!occupiedVoxel(voxel)) return 0.0f;
  const LocalVoxel l = local(voxel - min_voxel_);
  return occ_pool_[occ_index_[l.brick]].reflectivity[(l.bit_word << 6) | l.bit] / 255.0f;
}

float VoxelWorld::reflectivityAt(const Eigen::Vector3d& p_m) const {
  Eigen::Vector3i v;
  return voxelOf(p_m, v) ? reflectivityVoxel(v) : 0.0f;
}

void VoxelWorld::markKnownFree(const VoxelBox& voxels) {
  Eigen::Vector3i lo, hi;
  if (!clipLocal(voxels, lo, hi)) return;
  if (free_index_.empty()) free_index_.assign(occ_index_.size(), -1);
  forEachSliceMask(lo, hi, [&](int64_t brick, int z, uint64_t mask) {
    int32_t& index = free_index_[brick];
    if (index < 0) {
      index = static_cast<int32_t>(free_pool_.size());
      free_pool_.emplace_back();
    }
    free_pool_[index][z] |= mask;
  });
}

bool VoxelWorld::knownFreeVoxel(const Eigen::Vector3i& voxel) const {
  if (free_index_.empty() || !contains(voxel)) return false;
  const LocalVoxel l = local(voxel - min_voxel_);
  const int32_t index = free_index_[l.brick];
  return index >= 0 && ((free_pool_[index][l.bit_word] >> l.bit) & 1u);
}

bool VoxelWorld::knownFree(const Eigen::Vector3d& p_m) const {
  Eigen::Vector3i v;
  return voxelOf(p_m, v) && knownFreeVoxel(v);
}

size_t VoxelWorld::knownFreeCount() const {
  size_t n = 0;
  for (const BrickBits& bits : free_pool_) {
    for (uint64_t word : bits) n += std::popcount(word);
  }
  return n;
}

size_t VoxelWorld::memoryBytes() const {
  return occ_index_.capacity() * sizeof(int32_t) + occ_pool_.capacity() * sizeof(OccupiedBrick) +
         free_index_.capacity() * sizeof(int32_t) + free_pool_.capacity() * sizeof(BrickBits);
}

std::optional<RayHit> VoxelWorld::castRay(const Eigen::Vector3d& origin_m, const Eigen::Vector3d& unit_dir,
                                          double max_range_m) const {
  if (!origin_m.allFinite()) throw std::invalid_argument("castRay: origin must be finite");
  if (!unit_dir.allFinite() || std::abs(unit_dir.squaredNorm() - 1.0) > 1e-6) {
    throw std::invalid_argument("castRay: direction must be a unit vector");
  }
  if (!(max_range_m > 0.0)) throw std::invalid_argument("castRay: max_range_m must be > 0");

  // Work in local voxel coordinates (voxel faces on integers) with t in metres.
  double o[3], dv[3], t_delta[3];
  int step[3];
  double t_enter = -kInf, t_exit = kInf;
  int enter_axis = -1;
  for (int a = 0; a < 3; ++a) {
    o[a] = inv_voxel_ * origin_m[a] - min_voxel_[a];
    dv[a] = inv_voxel_ * unit_dir[a];
    step[a] = dv[a] > 0.0 ? 1 : (dv[a] < 0.0 ? -1 : 0);
    if (step[a] == 0) {
      if (!(o[a] >= 0.0 && o[a] < dims_[a])) return std::nullopt;  // parallel to and outside the slab
      t_delta[a] = kInf;
      continue;
    }
    t_delta[a] = 1.0 / std::abs(dv[a]);
    double t0 = -o[a] / dv[a], t1 = (dims_[a] - o[a]) / dv[a];
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > t_enter) {
      t_enter = t0;
      enter_axis = a;
    }
    t_exit = std::min(t_exit, t1);
  }
  const double t_limit = std::min(t_exit, max_range_m);
  const bool starts_inside = t_enter <= 0.0;
  double t = starts_inside ? 0.0 : t_enter;
  if (t >= t_limit) return std::nullopt;
  int axis = starts_inside ? -1 : enter_axis;

  // Voxel containing the ray at t; the entered axis is set exactly, the
  // others are clamped so rounding cannot leave the grid.
  int idx[3];
  for (int a = 0; a < 3; ++a) {
    if (a == axis) {
      idx[a] = step[a] > 0 ? 0 : dims_[a] - 1;
    } else {
      const double p = std::floor(o[a] + t * dv[a]);
      idx[a] = static_cast<int>(std::clamp<double>(p, 0.0, dims_[a] - 1));
    }
  }

  // Brick-level DDA state: t at which the ray crosses the next brick face per axis.
  int brick[3];
  double brick_t_max[3];
  auto brickFaceT = [&](int a) {
    if (step[a] == 0) return kInf;
    const int face = (brick[a] + (step[a] > 0 ? 1 : 0)) * kBrickEdge;
    return (face - o[a]) / dv[a];
  };
  for (int a = 0; a < 3; ++a) {
    brick[a] = idx[a] >> kBrickShift;
    brick_t_max[a] = brickFaceT(a);
  }

  for (;;) {
    const int32_t index = occ_index_[brickLinear(brick[0], brick[1], brick[2])];
    if (index >= 0 && occ_pool_[index].count != 0) {
      const OccupiedBrick& b = occ_pool_[index];
      int lo[3], hi[3];
      double t_max[3];
      for (int a = 0; a < 3; ++a) {
        lo[a] = brick[a] * kBrickEdge;
        hi[a] = std::min(lo[a] + kBrickEdge - 1, dims_[a] - 1);
        t_max[a] = step[a] == 0 ? kInf : ((idx[a] + (step[a] > 0 ? 1 : 0)) - o[a]) / dv[a];
      }
      // Voxel-level DDA inside the brick.
      for (;;) {
        const int lx = idx[0] - lo[0], ly = idx[1] - lo[1], lz = idx[2] - lo[2];
        if ((b.bits[lz] >> ((ly << kBrickShift) | lx)) & 1u) {
          RayHit hit;
          hit.reflectivity = b.reflectivity[(lz << 6) | (ly << kBrickShift) | lx] / 255.0f;
          hit.range_m = t;
          hit.point_m = origin_m + t * unit_dir;
          if (axis < 0) {
            hit.normal = -unit_dir;
          } else {
            hit.normal = Eigen::Vector3d::Zero();
            hit.normal[axis] = -step[axis];
            // Put the point exactly on the entered face.
            const int face = min_voxel_[axis] + idx[axis] + (step[axis] < 0 ? 1 : 0);
            hit.point_m[axis] = face * voxel_m_;
          }
          return hit;
        }
        const int a = t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
        if (t_max[a] >= t_limit) return std::nullopt;
        idx[a] += step[a];
        if (idx[a] < lo[a] || idx[a] > hi[a]) break;  // left the brick: continue at brick level
        t = t_max[a];
        axis = a;
        t_max[a] += t_delta[a];
      }
    }
    // Step to the next brick and find the voxel where the ray enters it.
    const int a = brick_t_max[0] < brick_t_max[1] ? (brick_t_max[0] < brick_t_max[2] ? 0 : 2)
                                                   : (brick_t_max[1] < brick_t_max[2] ? 1 : 2);
    t = brick_t_max[a];
    if (t >= t_limit) return std::nullopt;
    brick[a] += step[a];
    if (brick[a] < 0 || brick[a] >= brick_dims_[a]) return std::nullopt;
    brick_t_max[a] = brickFaceT(a);
    axis = a;
    for (int k = 0; k < 3; ++k) {
      const int first = brick[k] * kBrickEdge;
      const int last = std::min(first + kBrickEdge - 1, dims_[k] - 1);
      if (k == a) {
        idx[k] = step[k] > 0 ? first : last;
      } else {
        const double p = std::floor(o[k] + t * dv[k]);
        idx[k] = static_cast<int>(std::clamp<double>(p, first, last));
      }
    }
  }
}

}  // namespace rmap::sim
