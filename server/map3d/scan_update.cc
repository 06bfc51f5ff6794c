#include "map3d/scan_update.h"

#include <algorithm>
#include <limits>

#include "map3d/ray_traversal.h"

namespace rmap::map3d {
namespace {

/// kStopAtFreed: the run of already freed cells that stops a walk is a
/// quarter of the cells left to the sensor, at least 2, at most
/// OccupancyParams::stop_after_freed_cells.
constexpr int kCellsLeftPerRunCell = 4;
constexpr int kShortestRun = 2;

}  // namespace

BlockMarks& ScanUpdate::lookUp(const BlockKey& key) {
  uint32_t slot = index_.find(key);
  if (slot == BlockIndex::kMissing) {
    slot = static_cast<uint32_t>(blocks_.size());
    index_.insert(key, slot);
    blocks_.emplace_back();
    blocks_.back().key = key;
  }
  last_key_ = key;
  last_slot_ = slot;
  return blocks_[slot];
}

void ScanUpdate::gather(const Grid& grid, const OccupancyParams& params, const Eigen::Vector3f& sensor_origin_m,
                        std::span<const Eigen::Vector3f> points_m) {
  const bool beam = params.sensor_model == SensorModel::kBeam;
  const bool exact = params.free_space_tracing == FreeSpaceTracing::kOctomapExact;
  CellKey origin_cell;
  if (!grid.cellChecked(sensor_origin_m, origin_cell)) {
    stats_.points += points_m.size();
    stats_.rejected_points += points_m.size();
    return;
  }
  bool origin_freed = false;
  const int stop_run = std::max(kShortestRun, params.stop_after_freed_cells);
  // end_cell: the cell of end_m, already known to be addressable
  auto free = [&](const Eigen::Vector3f& end_m, const CellKey& end_cell) {
    if (exact) {
      traverseFreeCells(grid, sensor_origin_m, end_m, [this](const CellKey& c) { markFree(c); });
      return;
    }
    if (end_cell == origin_cell) return;
    walkBack(grid.resolution(), sensor_origin_m, origin_cell, end_m, end_cell, stop_run);
    if (!origin_freed) {
      markFree(origin_cell);
      origin_freed = true;
    }
  };
  for (const Eigen::Vector3f& p : points_m) {
    ++stats_.points;
    CellKey end;
    if (!grid.cellChecked(p, end)) {
      ++stats_.rejected_points;
      continue;
    }
    if (params.max_range_m >= 0.0) {
      const Eigen::Vector3f d = p - sensor_origin_m;
      const double range = std::sqrt(static_cast<double>(d.x() * d.x() + d.y() * d.y() + d.z() * d.z()));
      if (range > params.max_range_m) {
        ++stats_.max_range_rays;
        if (beam) {
          const Eigen::Vector3f dir = d / static_cast<float>(range);
          const Eigen::Vector3f truncated = sensor_origin_m + dir * static_cast<float>(params.max_range_m);
          CellKey truncated_cell;
          if (grid.cellChecked(truncated, truncated_cell)) free(truncated, truncated_cell);
        }
        continue;
      }
    }
    if (beam) free(p, end);
    markOccupied(end);
  }
}

void ScanUpdate::walkBack(double resolution_m, const Eigen::Vector3f& origin_m, const CellKey& origin_cell,
                          const Eigen::Vector3f& end_m, const CellKey& end_cell, int longest_run) {
  // The line end + t·(origin − end), t ∈ [0, 1]. Each step moves one axis one
  // cell towards the sensor's cell; an axis that got there is never chosen
  // again, so the walk reaches that cell in exactly `left` steps whatever the
  // rounding, and stops one step short of it.
  int32_t cell[3] = {end_cell.x, end_cell.y, end_cell.z};
  int32_t step[3];
  int32_t to_go[3];
  double t_max[3], t_delta[3];
  int left = 0;
  for (int a = 0; a < 3; ++a) {
    to_go[a] = std::abs(origin_cell[a] - cell[a]);
    left += to_go[a];
    step[a] = origin_cell[a] > cell[a] ? 1 : -1;
    if (to_go[a] == 0) {
      t_max[a] = t_delta[a] = std::numeric_limits<double>::infinity();
      continue;
    }
    const double inv = 1.0 / (static_cast<double>(origin_m[a]) - static_cast<double>(end_m[a]));
    const double border = (cell[a] + (step[a] > 0 ? 1 : 0)) * resolution_m;
    t_max[a] = (border - end_m[a]) * inv;
    t_delta[a] = resolution_m * std::abs(inv);
  }
  int freed_run = 0;
  while (--left > 0) {
    int dim;
    if (t_max[0] < t_max[1]) {
      dim = t_max[0] < t_max[2] ? 0 : 2;
    } else {
      dim = t_max[1] < t_max[2] ? 1 : 2;
    }
    cell[dim] += step[dim];
    t_max[dim] = --to_go[dim] == 0 ? std::numeric_limits<double>::infinity() : t_max[dim] + t_delta[dim];
    const CellKey c{cell[0], cell[1], cell[2]};
    BlockMarks& marks = marksOf(blockOf(c));
    const int i = localIndex(c);
    if (!marks.free.test(i)) {
      marks.free.set(i);
      freed_run = 0;
      continue;
    }
    // Close to the sensor a shorter run suffices: what is left of the walk is
    // short and crowded by other rays (measured in docs/BENCHMARKS.md).
    if (++freed_run >= std::clamp(left / kCellsLeftPerRunCell, kShortestRun, longest_run)) return;
  }
}

void ScanUpdate::merge(ScanUpdate&& other) {
  if (blocks_.empty()) {
    *this = std::move(other);
    return;
  }
  for (BlockMarks& m : other.blocks_) {
    BlockMarks& mine = marksOf(m.key);
    for (int w = 0; w < kBlockWords; ++w) {
      mine.free.words[w] |= m.free.words[w];
      mine.occupied.words[w] |= m.occupied.words[w];
    }
  }
  stats_.points += other.stats_.points;
  stats_.rejected_points += other.stats_.rejected_points;
  stats_.max_range_rays += other.stats_.max_range_rays;
}

void ScanUpdate::resolve() {
  stats_.occupied_cells = stats_.free_cells = 0;
  for (BlockMarks& m : blocks_) {
    for (int w = 0; w < kBlockWords; ++w) m.free.words[w] &= ~m.occupied.words[w];
    stats_.occupied_cells += m.occupied.count();
    stats_.free_cells += m.free.count();
  }
}

}  // namespace rmap::map3d
