#pragma once
/// @file scan_update.h
/// The cells one scan updates, gathered before the map is touched so that
/// each cell changes at most once per scan and occupied wins over free.

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <vector>

#include "map3d/block_index.h"
#include "map3d/cell_key.h"
#include "map3d/dense_cells.h"
#include "map3d/occupancy_params.h"

namespace rmap::map3d {

/// Free and occupied marks of one block for one scan.
struct BlockMarks {
  BlockKey key;
  BlockBits free;
  BlockBits occupied;
};

/// Counts of what a scan did; points rejected are reported, never silently dropped.
struct ScanStats {
  uint64_t points = 0;            ///< points given
  uint64_t rejected_points = 0;   ///< NaN/inf or outside the addressable range
  uint64_t max_range_rays = 0;    ///< rays truncated at max range (no endpoint)
  uint64_t occupied_cells = 0;    ///< distinct cells updated as hits
  uint64_t free_cells = 0;        ///< distinct cells updated as misses
};

class ScanUpdate {
 public:
  /// Gathers the update of points [begin, end) of a scan (world frame, metres).
  /// @param sensor_origin_m  must be addressable (checked by the caller)
  void gather(const Grid& grid, const OccupancyParams& params, const Eigen::Vector3f& sensor_origin_m,
              std::span<const Eigen::Vector3f> points_m);

  /// Adds the marks of another partial update (parallel gathering).
  void merge(ScanUpdate&& other);

  /// After gathering: clears free marks under occupied ones (occupied wins).
  void resolve();

  std::vector<BlockMarks>& blocks() { return blocks_; }
  const std::vector<BlockMarks>& blocks() const { return blocks_; }
  const ScanStats& stats() const { return stats_; }
  ScanStats& stats() { return stats_; }

 private:
  /// Consecutive cells of a ray mostly share a block, and so do the end
  /// cells of consecutive rays: each keeps its last block, and the hash
  /// lookup runs only when the block changes.
  BlockMarks& marksOf(const BlockKey& key) {
    if (!(key == last_key_)) {
      last_key_ = key;
      last_slot_ = slotOf(key);
    }
    return blocks_[last_slot_];
  }
  BlockMarks& endMarksOf(const BlockKey& key) {
    if (!(key == end_key_)) {
      end_key_ = key;
      end_slot_ = slotOf(key);
    }
    return blocks_[end_slot_];
  }
  /// Slot of a block's marks in blocks_, added when missing.
  uint32_t slotOf(const BlockKey& key);
  /// FreeSpaceTracing::kStopAtFreed: frees the cells between a ray's end cell
  /// and the sensor's cell (both excluded), walking back from the end until a
  /// run of cells earlier rays freed shows that the paths have merged.
  /// @param end_cell, origin_cell  the cells of end_m and origin_m, different
  /// @param end_marks  the marks of end_cell's block
  void walkBack(double resolution_m, const Eigen::Vector3f& origin_m, const CellKey& origin_cell,
                const Eigen::Vector3f& end_m, const CellKey& end_cell, BlockMarks& end_marks, int longest_run);
  void markFree(const CellKey& c) { marksOf(blockOf(c)).free.set(localIndex(c)); }
  void markOccupied(const CellKey& c) { endMarksOf(blockOf(c)).occupied.set(localIndex(c)); }

  std::vector<BlockMarks> blocks_;
  BlockIndex index_;
  BlockKey last_key_{INT32_MIN, INT32_MIN, INT32_MIN};
  uint32_t last_slot_ = 0;
  BlockKey end_key_{INT32_MIN, INT32_MIN, INT32_MIN};
  uint32_t end_slot_ = 0;
  ScanStats stats_;
};

}  // namespace rmap::map3d
