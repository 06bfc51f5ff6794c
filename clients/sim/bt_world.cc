#include "sim/bt_world.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rmap::sim {
namespace {

uint64_t splitmix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// Value noise: random values in [−1, 1] on the integer lattice, hashed from
/// (seed, octave, lattice point), blended with smoothstep weights.
class ValueNoise {
 public:
  ValueNoise(uint64_t seed, uint64_t octave) : key_(splitmix64(seed ^ splitmix64(octave))) {}

  double operator()(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d cell = p.array().floor();
    const Eigen::Vector3d f = p - cell;
    const Eigen::Vector3d w = f.array() * f.array() * (3.0 - 2.0 * f.array());
    const int64_t x = static_cast<int64_t>(cell.x()), y = static_cast<int64_t>(cell.y()), z = static_cast<int64_t>(cell.z());
    double sum = 0.0;
    for (int corner = 0; corner < 8; ++corner) {
      const int dx = corner & 1, dy = (corner >> 1) & 1, dz = corner >> 2;
      const double weight = (dx ? w.x() : 1.0 - w.x()) * (dy ? w.y() : 1.0 - w.y()) * (dz ? w.z() : 1.0 - w.z());
      sum += weight * lattice(x + dx, y + dy, z + dz);
    }
    return sum;
  }

 private:
  double lattice(int64_t x, int64_t y, int64_t z) const {
    uint64_t h = splitmix64(key_ ^ static_cast<uint64_t>(x));
    h = splitmix64(h ^ static_cast<uint64_t>(y));
    h = splitmix64(h ^ static_cast<uint64_t>(z));
    return static_cast<double>(h >> 11) * (2.0 / 9007199254740992.0) - 1.0;  // 53 bits → [−1, 1)
  }

  uint64_t key_;
};

}  // namespace

VoxelWorld worldFromBt(const map3d::BtTree& tree, float reflectivity_default, uint64_t seed) {
  if (!(tree.resolution_m > 0.0) || !std::isfinite(tree.resolution_m)) {
    throw std::invalid_argument("worldFromBt: tree resolution must be positive, got " + std::to_string(tree.resolution_m));
  }
  if (!(reflectivity_default > 0.0f && reflectivity_default <= 1.0f)) {
    throw std::invalid_argument("worldFromBt: reflectivity_default must be in (0, 1], got " +
                                std::to_string(reflectivity_default));
  }
  Eigen::Matrix<int64_t, 3, 1> lo = Eigen::Matrix<int64_t, 3, 1>::Constant(std::numeric_limits<int64_t>::max());
  Eigen::Matrix<int64_t, 3, 1> hi = Eigen::Matrix<int64_t, 3, 1>::Constant(std::numeric_limits<int64_t>::min());
  bool any_occupied = false;
  for (const map3d::BtLeaf& leaf : tree.leaves) {
    if (leaf.size_cells < 1) throw std::invalid_argument("worldFromBt: leaf with size_cells < 1");
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min<int64_t>(lo[a], leaf.min_cell[a]);
      hi[a] = std::max<int64_t>(hi[a], static_cast<int64_t>(leaf.min_cell[a]) + leaf.size_cells);
    }
    any_occupied |= leaf.occupied;
  }
  if (!any_occupied) throw std::invalid_argument("worldFromBt: the tree has no occupied leaf");
  const Eigen::Matrix<int64_t, 3, 1> extent = hi - lo;
  if (static_cast<double>(extent[0]) * extent[1] * extent[2] > static_cast<double>(VoxelWorld::kMaxVoxels) ||
      extent.maxCoeff() > std::numeric_limits<int32_t>::max()) {
    throw std::invalid_argument("worldFromBt: the leaves span more than VoxelWorld::kMaxVoxels cells");
  }
  VoxelWorld world(tree.resolution_m, lo.cast<int>(), extent.cast<int>());

  const ValueNoise coarse(seed, 0), fine(seed, 1);
  for (const map3d::BtLeaf& leaf : tree.leaves) {
    const Eigen::Vector3i first(leaf.min_cell.x, leaf.min_cell.y, leaf.min_cell.z);
    const VoxelBox cube(first, first + Eigen::Vector3i::Constant(leaf.size_cells - 1));
    if (!leaf.occupied) {
      world.markKnownFree(cube);
      continue;
    }
    for (int z = cube.min().z(); z <= cube.max().z(); ++z) {
      for (int y = cube.min().y(); y <= cube.max().y(); ++y) {
        for (int x = cube.min().x(); x <= cube.max().x(); ++x) {
          const Eigen::Vector3i v(x, y, z);
          const Eigen::Vector3d p = world.voxelCenter(v);
          const double n = 0.7 * coarse(p / 2.0) + 0.3 * fine(p / 0.5);
          const double rho = std::clamp(reflectivity_default * (1.0 + 0.6 * n), 0.02, 1.0);
          world.fillVoxels(VoxelBox(v, v), static_cast<float>(rho));
        }
      }
    }
  }
  return world;
}

}  // namespace rmap::sim
