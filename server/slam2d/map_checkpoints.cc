#include "slam2d/map_checkpoints.h"

#include <algorithm>
#include <unordered_set>

namespace rmap::slam2d {

void MapCheckpoints::offer(size_t keyframes, const GridMap2d& map) {
  if (max_count_ == 0 || keyframes == 0 || keyframes % spacing_ != 0) return;
  if (!checkpoints_.empty() && checkpoints_.back().keyframes >= keyframes) return;
  checkpoints_.push_back({keyframes, map});
  while (checkpoints_.size() > max_count_) {
    spacing_ *= 2;
    std::erase_if(checkpoints_, [&](const Checkpoint& c) { return c.keyframes % spacing_ != 0; });
  }
  size_t map_chunks = 0;
  map.forEachChunk([&](const void*) { ++map_chunks; });
  while (checkpoints_.size() > 1 && chunksOfTheirOwn(map) > kMaxOwnChunksPerMapChunk * map_chunks)
    checkpoints_.erase(checkpoints_.begin());
}

size_t MapCheckpoints::chunksOfTheirOwn(const GridMap2d& map) const {
  std::unordered_set<const void*> shared, own;
  map.forEachChunk([&](const void* chunk) { shared.insert(chunk); });
  for (const Checkpoint& c : checkpoints_)
    c.map.forEachChunk([&](const void* chunk) {
      if (!shared.contains(chunk)) own.insert(chunk);
    });
  return own.size();
}

const MapCheckpoints::Checkpoint* MapCheckpoints::latestUpTo(size_t keyframes) {
  const auto later = std::find_if(checkpoints_.begin(), checkpoints_.end(),
                                  [&](const Checkpoint& c) { return c.keyframes > keyframes; });
  checkpoints_.erase(later, checkpoints_.end());
  return checkpoints_.empty() ? nullptr : &checkpoints_.back();
}

}  // namespace rmap::slam2d
