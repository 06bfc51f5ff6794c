#include "map3d/scan_update.h"

#include <algorithm>
#include <cstdlib>
#include <limits>

#include "map3d/ray_traversal.h"

namespace rmap::map3d {
namespace {

/// kStopAtFreed: the run of already freed cells that stops a walk is a
/// quarter of the cells left to the sensor, at least 2, at most
/// OccupancyParams::stop_after_freed_cells.
constexpr int kCellsLeftPerRunCell = 4;
constexpr int kShortestRun = 2;

/// The rule above, checked at every cell of a run, solved once when the run
/// starts `left` cells before the sensor: the length k of the run that stops
/// the walk is the smallest k with
/// k >= clamp((left - k + 1) / kCellsLeftPerRunCell, kShortestRun, longest_run).
int stoppingRun(int left, int longest_run) {
  constexpr int d = kCellsLeftPerRunCell;
  const int k = left + 1 < d ? 1 : (left + 1 - d) / (d + 1) + 1;
  return std::max(kShortestRun, std::min(longest_run, k));
}

}  // namespace

uint32_t ScanUpdate::slotOf(const BlockKey& key) {
  uint32_t slot = index_.find(key);
  if (slot == BlockIndex::kMissing) {
    slot = static_cast<uint32_t>(blocks_.size());
    index_.insert(key, slot);
    blocks_.emplace_back();
    blocks_.back().key = key;
  }
  return slot;
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
  // hit: the end cell is an endpoint (not a ray truncated at max range)
  auto trace = [&](const Eigen::Vector3f& end_m, const CellKey& end_cell, bool hit) {
    if (exact) {
      traverseFreeCells(grid, sensor_origin_m, origin_cell, end_m, end_cell, [this](const CellKey& c) { markFree(c); });
      if (hit) markOccupied(end_cell);
      return;
    }
    BlockMarks& end_marks = endMarksOf(blockOf(end_cell));
    if (hit) end_marks.occupied.set(localIndex(end_cell));
    if (end_cell == origin_cell) return;
    walkBack(grid.resolution(), sensor_origin_m, origin_cell, end_m, end_cell, end_marks, stop_run);
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
          if (grid.cellChecked(truncated, truncated_cell)) trace(truncated, truncated_cell, false);
        }
        continue;
      }
    }
    if (beam) {
      trace(p, end, true);
    } else {
      markOccupied(end);
    }
  }
}

void ScanUpdate::walkBack(double resolution_m, const Eigen::Vector3f& origin_m, const CellKey& origin_cell,
                          const Eigen::Vector3f& end_m, const CellKey& end_cell, BlockMarks& end_marks,
                          int longest_run) {
  // The line end + t·(origin − end), t in [0, 1], in units of t: per axis the
  // next cell border (t_*) and the distance between borders (dt_*). An axis on
  // which both cells agree is never stepped. The walk takes exactly `left`
  // steps (the cells' Manhattan distance), so it needs no end test and `left`
  // is also the number of cells still to go.
  constexpr double kNever = std::numeric_limits<double>::infinity();
  int left = 0;
  auto setUp = [&](int a, double& t, double& dt, int& step) {
    const int32_t to_go = origin_cell[a] - end_cell[a];
    left += std::abs(to_go);
    if (to_go == 0) {
      t = dt = kNever;
      step = 0;
      return;
    }
    step = to_go > 0 ? 1 : -1;
    const double inv = 1.0 / (static_cast<double>(origin_m[a]) - static_cast<double>(end_m[a]));
    const double border_m = (end_cell[a] + (to_go > 0 ? 1 : 0)) * resolution_m;
    t = (border_m - static_cast<double>(end_m[a])) * inv;
    dt = resolution_m * std::abs(inv);
  };
  double tx, ty, tz, dtx, dty, dtz;
  int sx, sy, sz;
  setUp(0, tx, dtx, sx);
  setUp(1, ty, dty, sy);
  setUp(2, tz, dtz, sz);
  // The cell is tracked as its block and its index inside the block (x in
  // bits 0-3, y in 4-7, z in 8-11), so a step is an add to that index; the
  // step leaves the block when it flips the bit above its axis' four, and only
  // then is the block looked up.
  int32_t bx = end_cell.x >> kBlockShift, by = end_cell.y >> kBlockShift, bz = end_cell.z >> kBlockShift;
  int i = localIndex(end_cell);
  const int step_x = sx, step_y = sy * kBlockEdge, step_z = sz * kBlockEdge * kBlockEdge;
  constexpr int kXBits = kBlockEdge - 1, kYBits = kXBits << kBlockShift, kZBits = kYBits << kBlockShift;
  uint64_t* free_words = end_marks.free.words.data();
  int freed_run = 0;
  int stop_run = 0;
  while (--left > 0) {
    if (tx < ty && tx < tz) {
      tx += dtx;
      const int moved = i + step_x;
      if ((moved ^ i) & (kXBits + 1)) {
        i = (i & ~kXBits) | (moved & kXBits);
        bx += sx;
        free_words = marksOf({bx, by, bz}).free.words.data();
      } else {
        i = moved;
      }
    } else if (ty < tz) {
      ty += dty;
      const int moved = i + step_y;
      if ((moved ^ i) & (kYBits + kBlockEdge)) {
        i = (i & ~kYBits) | (moved & kYBits);
        by += sy;
        free_words = marksOf({bx, by, bz}).free.words.data();
      } else {
        i = moved;
      }
    } else {
      tz += dtz;
      const int moved = i + step_z;
      if ((moved ^ i) & (kZBits + kBlockEdge * kBlockEdge)) {
        i = (i & ~kZBits) | (moved & kZBits);
        bz += sz;
        free_words = marksOf({bx, by, bz}).free.words.data();
      } else {
        i = moved;
      }
    }
    uint64_t& word = free_words[i >> 6];
    const uint64_t bit = uint64_t{1} << (i & 63);
    if (!(word & bit)) {
      word |= bit;
      freed_run = 0;
      continue;
    }
    // Close to the sensor a shorter run suffices: what is left of the walk is
    // short and crowded by other rays (measured in docs/BENCHMARKS.md).
    if (freed_run == 0) stop_run = stoppingRun(left, longest_run);
    if (++freed_run >= stop_run) return;
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
