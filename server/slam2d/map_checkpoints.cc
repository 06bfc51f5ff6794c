#include "slam2d/map_checkpoints.h"

#include <algorithm>

namespace rmap::slam2d {

void MapCheckpoints::offer(size_t keyframes, const GridMap2d& map) {
  if (max_count_ == 0 || keyframes == 0 || keyframes % spacing_ != 0) return;
  if (!checkpoints_.empty() && checkpoints_.back().keyframes >= keyframes) return;
  checkpoints_.push_back({keyframes, map});
  while (checkpoints_.size() > max_count_) {
    spacing_ *= 2;
    std::erase_if(checkpoints_, [&](const Checkpoint& c) { return c.keyframes % spacing_ != 0; });
  }
}

const MapCheckpoints::Checkpoint* MapCheckpoints::latestUpTo(size_t keyframes) {
  const auto later = std::find_if(checkpoints_.begin(), checkpoints_.end(),
                                  [&](const Checkpoint& c) { return c.keyframes > keyframes; });
  checkpoints_.erase(later, checkpoints_.end());
  return checkpoints_.empty() ? nullptr : &checkpoints_.back();
}

}  // namespace rmap::slam2d
