#include "sim/navigable.h"

#include <algorithm>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

namespace rmap::sim {
namespace {

/// Occupancy of every cell column as a bitset over the grid's z range (OR
/// over the cell's voxel columns, so obstacles are never missed).
class ColumnBits {
 public:
  ColumnBits(int cells_x, int cells_y, int nz) : words_((nz + 63) / 64), bits_(size_t(cells_x) * cells_y * words_, 0) {}

  void set(size_t cell, int z) { bits_[cell * words_ + (z >> 6)] |= uint64_t{1} << (z & 63); }
  bool test(size_t cell, int z) const { return (bits_[cell * words_ + (z >> 6)] >> (z & 63)) & 1u; }

  /// Any bit set in [lo, hi] (local z, 0 ≤ lo, hi < nz)?
  bool any(size_t cell, int lo, int hi) const {
    if (lo > hi) return false;
    const uint64_t* w = &bits_[cell * words_];
    for (int word = lo >> 6; word <= hi >> 6; ++word) {
      const int first = std::max(lo, word * 64) - word * 64, last = std::min(hi, word * 64 + 63) - word * 64;
      const uint64_t mask = (last == 63 ? ~uint64_t{0} : ((uint64_t{1} << (last + 1)) - 1)) & ~((uint64_t{1} << first) - 1);
      if (w[word] & mask) return true;
    }
    return false;
  }

 private:
  int words_;
  std::vector<uint64_t> bits_;
};

}  // namespace

void NavigableOptions::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("NavigableOptions: " + what); };
  if (!(clearance_m > 0.0) || !std::isfinite(clearance_m)) fail("clearance_m must be > 0");
  if (!(sensor_height_m >= clearance_m) || !std::isfinite(sensor_height_m)) {
    fail("sensor_height_m must be ≥ clearance_m (the sensor keeps clearance from the floor too)");
  }
  if (!(body_bottom_m >= 0.0) || !std::isfinite(body_bottom_m)) fail("body_bottom_m must be ≥ 0");
  if (!(max_step_m >= 0.0) || !std::isfinite(max_step_m)) fail("max_step_m must be ≥ 0");
  if (!(cell_m > 0.0) || !std::isfinite(cell_m)) fail("cell_m must be > 0");
}

NavigableSpace::NavigableSpace(const VoxelWorld& world, const NavigableOptions& options)
    : options_(options), voxel_m_(world.voxelSize()), min_voxel_(world.minVoxel()), dims_(world.dims()) {
  options_.validate();
  const double v = voxel_m_;
  cell_voxels_ = std::max(1, static_cast<int>(std::lround(options_.cell_m / v)));
  cell_m_ = cell_voxels_ * v;
  cells_x_ = (dims_.x() + cell_voxels_ - 1) / cell_voxels_;
  cells_y_ = (dims_.y() + cell_voxels_ - 1) / cell_voxels_;
  max_step_voxels_ = static_cast<int>(std::floor(options_.max_step_m / v + 1e-9));
  const int nz = dims_.z();

  ColumnBits columns(cells_x_, cells_y_, nz);
  world.forEachOccupiedVoxel([&](const Eigen::Vector3i& voxel) {
    const Eigen::Vector3i l = voxel - min_voxel_;
    columns.set(static_cast<size_t>(l.y() / cell_voxels_) * cells_x_ + l.x() / cell_voxels_, l.z());
  });

  // Cells whose rectangle comes within clearance of the centre cell's rectangle.
  std::vector<Eigen::Vector2i> reach;
  const int r = static_cast<int>(std::ceil(options_.clearance_m / cell_m_)) + 1;
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      const double gx = std::max(0, std::abs(dx) - 1) * cell_m_, gy = std::max(0, std::abs(dy) - 1) * cell_m_;
      if (gx * gx + gy * gy <= options_.clearance_m * options_.clearance_m) reach.emplace_back(dx, dy);
    }
  }

  const double inv = 1.0 / v;
  const double band_bottom_m = std::min(options_.body_bottom_m, options_.sensor_height_m - options_.clearance_m);
  cell_start_.assign(static_cast<size_t>(cells_x_) * cells_y_ + 1, 0);
  for (int cy = 0; cy < cells_y_; ++cy) {
    for (int cx = 0; cx < cells_x_; ++cx) {
      const size_t cell = static_cast<size_t>(cy) * cells_x_ + cx;
      cell_start_[cell] = static_cast<int>(nodes_.size());
      for (int k = 0; k + 1 < nz; ++k) {
        if (!columns.test(cell, k) || columns.test(cell, k + 1)) continue;
        const double surface_m = (min_voxel_.z() + k + 1) * v;
        const double sensor_m = surface_m + options_.sensor_height_m;
        const int top = static_cast<int>(std::floor((sensor_m + options_.clearance_m) * inv)) - min_voxel_.z();
        if (top >= nz) continue;  // the body would stick out of the grid
        const int band_lo =
            std::max(k + 1, static_cast<int>(std::floor((surface_m + band_bottom_m) * inv)) - min_voxel_.z());
        if (columns.any(cell, k + 1, top)) continue;
        bool clear = true;
        for (const Eigen::Vector2i& d : reach) {
          const int ox = cx + d.x(), oy = cy + d.y();
          if (ox < 0 || oy < 0 || ox >= cells_x_ || oy >= cells_y_) continue;  // outside the grid: free
          if (columns.any(static_cast<size_t>(oy) * cells_x_ + ox, band_lo, top)) {
            clear = false;
            break;
          }
        }
        if (!clear) continue;
        if (world.hasKnownFree()) {
          const int zs = static_cast<int>(std::floor(sensor_m * inv));
          const int x0 = min_voxel_.x() + cx * cell_voxels_, y0 = min_voxel_.y() + cy * cell_voxels_;
          const int x1 = std::min(x0 + cell_voxels_, min_voxel_.x() + dims_.x());
          const int y1 = std::min(y0 + cell_voxels_, min_voxel_.y() + dims_.y());
          for (int y = y0; y < y1 && clear; ++y) {
            for (int x = x0; x < x1 && clear; ++x) clear = world.knownFreeVoxel(Eigen::Vector3i(x, y, zs));
          }
          if (!clear) continue;
        }
        nodes_.push_back({cx, cy, min_voxel_.z() + k});
      }
    }
  }
  cell_start_.back() = static_cast<int>(nodes_.size());

  // Connected components by breadth-first search, then renumbered by size.
  component_.assign(nodes_.size(), -1);
  std::vector<size_t> sizes;
  std::vector<int> queue;
  for (size_t seed = 0; seed < nodes_.size(); ++seed) {
    if (component_[seed] >= 0) continue;
    const int id = static_cast<int>(sizes.size());
    component_[seed] = id;
    queue.assign(1, static_cast<int>(seed));
    for (size_t head = 0; head < queue.size(); ++head) {
      forEachNeighbour(queue[head], [&](int next, double) {
        if (component_[next] < 0) {
          component_[next] = id;
          queue.push_back(next);
        }
      });
    }
    sizes.push_back(queue.size());
  }
  std::vector<int> order(sizes.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return sizes[a] > sizes[b]; });
  std::vector<int> rank(sizes.size());
  component_sizes_.resize(sizes.size());
  for (size_t i = 0; i < order.size(); ++i) {
    rank[order[i]] = static_cast<int>(i);
    component_sizes_[i] = sizes[order[i]];
  }
  for (int& c : component_) c = rank[c];
}

Eigen::AlignedBox2d NavigableSpace::cellBox(int cx, int cy) const {
  const Eigen::Vector2d lo((min_voxel_.x() + cx * cell_voxels_) * voxel_m_, (min_voxel_.y() + cy * cell_voxels_) * voxel_m_);
  const Eigen::Vector2d grid_hi((min_voxel_.x() + dims_.x()) * voxel_m_, (min_voxel_.y() + dims_.y()) * voxel_m_);
  return {lo, (lo + Eigen::Vector2d::Constant(cell_m_)).cwiseMin(grid_hi)};
}

bool NavigableSpace::cellOf(const Eigen::Vector2d& xy_m, int& cx, int& cy) const {
  const double inv = 1.0 / voxel_m_;  // VoxelWorld's arithmetic, so both agree on boundaries
  const double lx = std::floor(inv * xy_m.x()) - min_voxel_.x();
  const double ly = std::floor(inv * xy_m.y()) - min_voxel_.y();
  if (!(lx >= 0 && ly >= 0 && lx < dims_.x() && ly < dims_.y())) return false;
  cx = static_cast<int>(lx) / cell_voxels_;
  cy = static_cast<int>(ly) / cell_voxels_;
  return true;
}

Eigen::Vector3d NavigableSpace::sensorPosition(int node) const {
  const Eigen::Vector2d centre = cellBox(nodes_[node].cx, nodes_[node].cy).center();
  return {centre.x(), centre.y(), sensorZ(node)};
}

int NavigableSpace::nodeNear(int cx, int cy, int surface_voxel) const {
  if (cx < 0 || cy < 0 || cx >= cells_x_ || cy >= cells_y_) return -1;
  const auto [first, last] = nodesInCell(cx, cy);
  int best = -1, best_gap = max_step_voxels_ + 1;
  for (int i = first; i < last; ++i) {
    const int gap = std::abs(nodes_[i].surface_voxel - surface_voxel);
    if (gap < best_gap) {
      best = i;
      best_gap = gap;
    }
  }
  return best;
}

bool NavigableSpace::compatible(int cx, int cy, int k1, int k2) const {
  const auto [first, last] = nodesInCell(cx, cy);
  for (int i = first; i < last; ++i) {
    const int k = nodes_[i].surface_voxel;
    if (std::abs(k - k1) <= max_step_voxels_ && std::abs(k - k2) <= max_step_voxels_) return true;
  }
  return false;
}

double NavigableSpace::dominantFloorZ() const {
  if (nodes_.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::map<int, size_t> histogram;
  for (size_t i = 0; i < nodes_.size(); ++i) {
    if (component_[i] == 0) ++histogram[nodes_[i].surface_voxel];
  }
  const auto mode = std::max_element(histogram.begin(), histogram.end(),
                                     [](const auto& a, const auto& b) { return a.second < b.second; });
  return (mode->first + 1) * voxel_m_;
}

}  // namespace rmap::sim
