#pragma once
/// @file cuboid_map.h
/// Variable-resolution 3D occupancy map made of axis-aligned rectangular
/// cuboids ("hot dense, cold cuboid").
///
/// The world is cut into blocks of 16³ base cells kept in a hash map. A block
/// being updated is dense (a float log-odds per cell) so rays integrate fast;
/// a block left alone for `FusionParams::fuse_after_scans` scans is fused into
/// maximal cuboids of cells with the same state and log-odds within the fusion
/// tolerance, 8 bytes each. An update to a fused block expands it again, so
/// cuboids split wherever new evidence disagrees. Unknown space is not stored.
///
/// Thread safety: one writer (insertScan, fuseAll, import) and any number of
/// concurrent readers. Rays of a scan are traced without the lock; only the
/// application of the gathered cell updates excludes readers.
///
/// No I/O: serialisation lives in map_file.h and octomap_bt.h.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <shared_mutex>
#include <span>
#include <unordered_map>
#include <vector>

#include "map3d/cell_key.h"
#include "map3d/cuboid.h"
#include "map3d/dense_cells.h"
#include "map3d/occupancy_params.h"
#include "map3d/scan_update.h"

namespace rmap::map3d {

enum class CellState : uint8_t { kUnknown, kFree, kOccupied };
const char* toString(CellState state);

/// Answer to a point query.
struct CellQuery {
  CellState state = CellState::kUnknown;
  float log_odds = 0.0f;     ///< meaningless when unknown
  double probability = 0.5;  ///< occupancy probability; 0.5 when unknown
  CuboidBox cuboid;          ///< the stored cuboid holding the cell (one cell in a hot block)
};

/// Answer to a ray cast.
struct RayCastResult {
  enum class Outcome : uint8_t {
    kHitOccupied,  ///< an occupied cell was reached
    kHitUnknown,   ///< an unknown cell stopped the ray (ignore_unknown = false)
    kMaxRange,     ///< nothing occupied within max range
    kInvalid,      ///< origin/direction not finite, or the ray leaves the addressable range at once
  };
  Outcome outcome = Outcome::kInvalid;
  CellKey cell;         ///< the cell that stopped the ray
  double distance_m = 0.0;  ///< from the origin to the entry of that cell
};

/// How a scan with NaN/inf or unaddressable points is handled.
enum class InvalidPoints : uint8_t {
  kReject,  ///< throw std::invalid_argument, map unchanged (default)
  kSkip,    ///< drop those points, count them in ScanStats::rejected_points
};

struct InsertOptions {
  int threads = 1;  ///< threads tracing rays, >= 1
  InvalidPoints invalid_points = InvalidPoints::kReject;
};

struct MapStats {
  uint64_t blocks = 0;        ///< allocated blocks (hot + fused)
  uint64_t hot_blocks = 0;    ///< blocks held dense
  uint64_t cuboids = 0;       ///< stored cuboids; each known cell of a hot block counts as one
  uint64_t known_cells = 0;   ///< observed base cells
  uint64_t occupied_cells = 0;
  uint64_t memory_bytes = 0;  ///< every allocation the map holds (see memoryBytes)
  uint64_t scans = 0;         ///< scans integrated
  uint64_t version = 0;       ///< bumped by every change
};

/// One allocated block in storage form, for serialisation and tiles.
struct BlockView {
  BlockKey key;
  uint64_t version = 0;              ///< map version of its last change
  std::span<const PackedCuboid> cuboids;
};

class CuboidMap {
 public:
  /// @param resolution_m  base cell edge in metres, finite and > 0
  /// @throws std::invalid_argument for a bad resolution or parameters
  explicit CuboidMap(double resolution_m, const OccupancyParams& occupancy = {}, const FusionParams& fusion = {});
  ~CuboidMap();
  CuboidMap(const CuboidMap&) = delete;
  CuboidMap& operator=(const CuboidMap&) = delete;

  const Grid& grid() const { return grid_; }
  double resolution() const { return grid_.resolution(); }
  const OccupancyParams& occupancyParams() const { return occupancy_; }
  const FusionParams& fusionParams() const { return fusion_; }

  /// Integrates one scan: a ray from the sensor origin to every point.
  /// @param sensor_origin_m  world frame, metres, must be addressable
  /// @param points_m         world frame, metres; must not be empty
  /// @throws std::invalid_argument (map unchanged) for an empty scan, a bad
  ///         origin, or invalid points under InvalidPoints::kReject
  ScanStats insertScan(const Eigen::Vector3f& sensor_origin_m, std::span<const Eigen::Vector3f> points_m,
                       const InsertOptions& options = {});

  /// Fuses every hot block now (e.g. before measuring or saving).
  /// @param threads  threads fusing blocks, >= 1
  void fuseAll(int threads = 1);

  CellQuery query(const Eigen::Vector3d& point_m) const;
  CellQuery queryCell(const CellKey& cell) const;

  /// Calls fn(const CuboidBox&) for each stored cuboid that intersects the
  /// inclusive cell range [min, max] (cuboids are not clipped); hot blocks are
  /// fused on the fly with the map's tolerance, without changing them. Stops
  /// when fn returns false. Blocks are visited in no particular order.
  void forEachCuboid(const CellKey& min, const CellKey& max, const std::function<bool(const CuboidBox&)>& fn) const;
  /// Cuboids intersecting an axis-aligned box given in metres.
  std::vector<CuboidBox> queryBox(const Eigen::AlignedBox3d& box_m, size_t limit = SIZE_MAX) const;

  /// Cuboids of a coarser level of detail over [min, max]: level L has cells of
  /// 2^L base cells; a coarse cell is known if any finer cell is and takes the
  /// maximum log-odds below it (conservative: occupied if any finer cell is).
  /// Coarse cells are fused like blocks. Level 0 equals forEachCuboid.
  /// @param level  0..16
  std::vector<CuboidBox> levelOfDetail(int level, const CellKey& min, const CellKey& max) const;

  /// Casts a ray until it reaches an occupied cell.
  /// @param direction       need not be normalised, must be non-zero
  /// @param max_range_m     metres, > 0
  /// @param ignore_unknown  pass through unknown cells instead of stopping
  RayCastResult castRay(const Eigen::Vector3d& origin_m, const Eigen::Vector3d& direction, double max_range_m,
                        bool ignore_unknown) const;

  /// Calls fn(cell, log_odds) for every known base cell.
  void forEachKnownCell(const std::function<void(const CellKey&, float)>& fn) const;

  /// Calls fn for every block in storage form (hot blocks fused on the fly).
  void forEachBlock(const std::function<void(const BlockView&)>& fn) const;

  /// Calls fn(key, version) for every allocated block, cheaply (no fusion):
  /// to find what changed since a version (tiles, change notices).
  void forEachBlockVersion(const std::function<void(const BlockKey&, uint64_t version)>& fn) const;

  /// Replaces whole blocks (import, loading a file). Cuboids must lie in the
  /// block, not overlap one another and carry finite log-odds within the clamps.
  /// @throws std::invalid_argument naming the first bad block; the map is unchanged then
  void replaceBlocks(std::vector<std::pair<BlockKey, std::vector<PackedCuboid>>> blocks);

  /// Sets cuboids of cells to a value (e.g. import of `.bt` leaves), merged
  /// with what the touched blocks held. Boxes must be addressable.
  /// @throws std::invalid_argument, map unchanged
  void setCuboids(std::span<const CuboidBox> boxes);

  /// Rewrites every cell of the inclusive range [min, max] with value(cell):
  /// a log-odds (clamped to the map's limits) or nullopt for unknown (the
  /// cell's evidence is erased). For content derived elsewhere and put in
  /// again, e.g. the planar rows of corrected 2D scans. Touched blocks are
  /// fused at once; blocks that would hold nothing known are not created.
  /// Cost O(cells in the range).
  /// @throws std::invalid_argument (map unchanged) for a range outside the
  ///         addressable cells, inverted, or a non-finite value
  void rewriteCells(const CellKey& min, const CellKey& max,
                    const std::function<std::optional<float>(const CellKey&)>& value);

  /// Cell range of all known cells; false when the map is empty.
  bool bounds(CellKey& min, CellKey& max) const;

  MapStats stats() const;
  /// Bytes of every allocation: the hash table's buckets and nodes, the
  /// cuboid arrays (capacity), dense blocks and the hot-block list.
  uint64_t memoryBytes() const;
  uint64_t version() const;

 private:
  struct Block;
  CellQuery queryCellLocked(const CellKey& cell) const;
  Block& findOrCreate(const BlockKey& key);
  /// A hot block for writing: fused ones are expanded.
  Block& blockForWrite(const BlockKey& key);
  /// Gives a fused block its dense cells (not yet filled) and lists it as hot.
  void makeHot(Block& block);
  void fillFromCuboids(Block& block);
  /// Fuses hot blocks (in parallel) and takes them off the hot list.
  void fuseBlocks(const std::vector<Block*>& blocks, int threads);
  void fuseColdBlocks(int threads);
  void applyUpdate(const ScanUpdate& update, int threads);
  uint64_t memoryBytesLocked() const;

  Grid grid_;
  OccupancyParams occupancy_;
  FusionParams fusion_;
  mutable std::shared_mutex mutex_;
  std::unordered_map<BlockKey, std::unique_ptr<Block>, BlockKeyHash> blocks_;
  std::vector<Block*> hot_;  ///< blocks in dense form
  uint64_t scans_ = 0;
  uint64_t version_ = 0;
};

}  // namespace rmap::map3d
