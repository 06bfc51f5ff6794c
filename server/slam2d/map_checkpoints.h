#pragma once
/// @file map_checkpoints.h
/// Copies of the 2D map as it stood after its first k keyframes. A loop
/// correction mostly moves the newer part of the trajectory: the map is then
/// rendered again from the last copy before the first keyframe that moved,
/// not from the first keyframe (raw intel: 7× fewer keyframe insertions).
/// Copies share the chunks neither side wrote since (ChunkedGrid), so one
/// costs about the area mapped after it. The oldest are dropped when the
/// copies' own chunks outnumber the map's kMaxOwnChunksPerMapChunk times (a
/// robot patrolling its map over and over rewrites every chunk between copies).

#include <cstddef>
#include <vector>

#include "slam2d/grid_map.h"

namespace rmap::slam2d {

class MapCheckpoints {
 public:
  struct Checkpoint {
    size_t keyframes;  ///< the map holds keyframes [0, keyframes)
    GridMap2d map;
  };

  /// Memory bound of the copies, in chunks of their own per chunk of the map,
  /// checked as a copy is taken (the map's writes until the next copy may add
  /// one map's worth). At 1 raw intel re-rendered 3.6× the keyframes it does at 4.
  static constexpr size_t kMaxOwnChunksPerMapChunk = 4;

  /// @param max_count  copies kept at most; 0 keeps none. Their spacing (in
  ///   keyframes, 8 at first) doubles whenever one more would be too many.
  explicit MapCheckpoints(size_t max_count) : max_count_(max_count) {}

  /// Keeps a copy of `map`, which holds keyframes [0, keyframes), when
  /// `keyframes` falls on the spacing and is past the newest copy; then drops
  /// the oldest copies while their own chunks exceed the memory bound.
  void offer(size_t keyframes, const GridMap2d& map);
  /// Chunks the copies hold that `map` does not share: what they cost beyond it.
  size_t chunksOfTheirOwn(const GridMap2d& map) const;
  /// The newest copy holding at most the first `keyframes` keyframes, nullptr
  /// when none; newer copies are dropped (they hold keyframes that moved).
  const Checkpoint* latestUpTo(size_t keyframes);
  /// Drops every copy (the keyframes would now render otherwise, e.g. with a new calibration).
  void clear() { checkpoints_.clear(); }

  size_t size() const { return checkpoints_.size(); }
  size_t spacing() const { return spacing_; }

 private:
  size_t max_count_;
  size_t spacing_ = 8;
  std::vector<Checkpoint> checkpoints_;  ///< by keyframe count, increasing
};

}  // namespace rmap::slam2d
