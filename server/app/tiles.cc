#include "app/tiles.h"

#include <algorithm>
#include <unordered_set>

namespace rmap::app {

namespace {

/// Floor division for negative block coordinates.
int32_t floorDiv(int64_t a, int64_t b) { return static_cast<int32_t>(a >= 0 ? a / b : -((-a + b - 1) / b)); }

}  // namespace

bool tileCellRange(const TileKey& key, map3d::CellKey& min, map3d::CellKey& max) {
  const int64_t edge = tileEdgeBaseCells(key.level);
  const int32_t xyz[3] = {key.x, key.y, key.z};
  for (int a = 0; a < 3; ++a) {
    const int64_t lo = std::max<int64_t>(xyz[a] * edge, -map3d::kCellLimit);
    const int64_t hi = std::min<int64_t>(xyz[a] * edge + edge - 1, map3d::kCellLimit - 1);
    if (lo > hi) return false;
    min[a] = static_cast<int32_t>(lo);
    max[a] = static_cast<int32_t>(hi);
  }
  return true;
}

std::vector<map3d::CuboidBox> tileCuboids(const map3d::CuboidMap& map, const TileKey& key) {
  map3d::CellKey min, max;
  if (!tileCellRange(key, min, max)) return {};
  return map.levelOfDetail(key.level, min, max);
}

std::vector<TileVersion> TileIndex::update(const map3d::CuboidMap& map) {
  std::lock_guard lock(mutex_);
  const uint64_t map_version = map.version();
  std::unordered_set<TileKey, TileKeyHash> changed;
  std::vector<TileVersion> out;
  if (map_version == seen_version_) return out;
  const uint64_t since = seen_version_;
  map.forEachBlockVersion([&](const map3d::BlockKey& block, uint64_t version) {
    if (version <= since) return;
    const int32_t b[3] = {block.x, block.y, block.z};
    for (int level = 0; level < kTileLevels; ++level) {
      const int64_t blocks_per_tile = tileEdgeBaseCells(level) / map3d::kBlockEdge;
      const TileKey key{level, floorDiv(b[0], blocks_per_tile), floorDiv(b[1], blocks_per_tile),
                        floorDiv(b[2], blocks_per_tile)};
      uint64_t& v = versions_[key];
      v = std::max(v, version);
      changed.insert(key);
    }
  });
  seen_version_ = map_version;
  out.reserve(changed.size());
  for (const TileKey& key : changed) out.push_back({key, versions_[key]});
  return out;
}

std::optional<uint64_t> TileIndex::version(const TileKey& key) const {
  std::lock_guard lock(mutex_);
  const auto it = versions_.find(key);
  if (it == versions_.end()) return std::nullopt;
  return it->second;
}

std::vector<TileVersion> TileIndex::tiles(int level) const {
  std::lock_guard lock(mutex_);
  std::vector<TileVersion> out;
  for (const auto& [key, version] : versions_) {
    if (key.level == level) out.push_back({key, version});
  }
  std::sort(out.begin(), out.end(), [](const TileVersion& a, const TileVersion& b) {
    return std::tie(a.key.z, a.key.y, a.key.x) < std::tie(b.key.z, b.key.y, b.key.x);
  });
  return out;
}

uint64_t TileIndex::mapVersion() const {
  std::lock_guard lock(mutex_);
  return seen_version_;
}

}  // namespace rmap::app
