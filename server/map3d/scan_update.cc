#include "map3d/scan_update.h"

#include <algorithm>

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
  auto free = [&](const Eigen::Vector3f& end_m, const CellKey& end_cell) {
    if (exact) {
      traverseFreeCells(grid, sensor_origin_m, origin_cell, end_m, end_cell, [this](const CellKey& c) { markFree(c); });
      return;
    }
    // Walk back from the end; the walk's first cell is the end cell itself, and
    // it never reaches the sensor's cell, which is freed once below.
    bool first = true;
    bool left_origin = false;
    int freed_run = 0;
    traverseFreeCells(grid, end_m, end_cell, sensor_origin_m, origin_cell, [&](const CellKey& c) {
      left_origin = true;
      if (first) {
        first = false;
        return true;
      }
      BlockMarks& marks = marksOf(blockOf(c));
      const int i = localIndex(c);
      if (!marks.free.test(i)) {
        marks.free.set(i);
        freed_run = 0;
        return true;
      }
      // Close to the sensor a shorter run suffices: what is left of the walk is
      // short and crowded by other rays (measured in docs/BENCHMARKS.md).
      const int cells_left =
          std::abs(c.x - origin_cell.x) + std::abs(c.y - origin_cell.y) + std::abs(c.z - origin_cell.z);
      return ++freed_run < std::clamp(cells_left / kCellsLeftPerRunCell, kShortestRun, stop_run);
    });
    if (left_origin && !origin_freed) {
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
