#pragma once
/// @file tiles.h
/// 3D tiles of a cuboid map. A tile of level L holds the map at level of
/// detail L (cells of 2^L base cells) over a cube of kTileEdgeCells cells of
/// that level, i.e. kTileEdgeCells·2^L base cells per axis; tile (x, y, z)
/// covers base cells [x·E, (x+1)·E) with E that edge. Tiles are aligned to
/// blocks, so a level-0 tile holds whole cuboids. A tile's version is the map
/// version of the last change inside it: an ETag and a change notice.

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "map3d/cuboid_map.h"

namespace rmap::app {

inline constexpr int kTileEdgeCells = 64;
inline constexpr int kTileLevels = 7;  ///< levels 0..6

struct TileKey {
  int level = 0;
  int32_t x = 0, y = 0, z = 0;
  bool operator==(const TileKey&) const = default;
};

struct TileKeyHash {
  size_t operator()(const TileKey& k) const {
    return map3d::BlockKeyHash{}(map3d::BlockKey{k.x, k.y, k.z}) * 31u + static_cast<size_t>(k.level);
  }
};

struct TileVersion {
  TileKey key;
  uint64_t version = 0;
};

/// Base-cell edge of a tile at `level`.
inline int64_t tileEdgeBaseCells(int level) { return int64_t{kTileEdgeCells} << level; }

/// Inclusive base-cell range of a tile, clipped to the addressable cells.
/// @return false (min, max unspecified) when the tile holds no addressable cell
bool tileCellRange(const TileKey& key, map3d::CellKey& min, map3d::CellKey& max);

/// Cuboids of one tile (at the tile's level of detail).
std::vector<map3d::CuboidBox> tileCuboids(const map3d::CuboidMap& map, const TileKey& key);

/// Versions of every non-empty tile of a map, updated from the map's block
/// versions. Thread-safe.
class TileIndex {
 public:
  /// Scans the map's blocks for changes since the last call and returns the
  /// tiles (all levels) whose version changed.
  std::vector<TileVersion> update(const map3d::CuboidMap& map);
  std::optional<uint64_t> version(const TileKey& key) const;
  /// Every known tile of a level.
  std::vector<TileVersion> tiles(int level) const;
  /// Map version the index reflects.
  uint64_t mapVersion() const;

 private:
  mutable std::mutex mutex_;
  uint64_t seen_version_ = 0;
  std::unordered_map<TileKey, uint64_t, TileKeyHash> versions_;
};

}  // namespace rmap::app
