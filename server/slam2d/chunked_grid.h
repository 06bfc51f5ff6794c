#pragma once
/// @file chunked_grid.h
/// Unbounded 2D array of cells stored in square chunks that are allocated on
/// first write, so a map grows in every direction as the robot goes.
///
/// Chunks are found through an open-addressing hash table (linear probing,
/// load ≤ 1/2) keyed by chunk indices: a read is one multiply, usually one
/// probe and two loads, which keeps the scan matcher's hot path cheap while
/// robots far apart cost nothing for the space between them.
///
/// A copy shares its chunks with the original (a snapshot costs the hash
/// table only); the first write to a shared chunk copies that chunk. So a
/// cell stays in place across writes unless a copy of the grid was taken
/// since; a Cursor must not outlive a copy. Reads are const and may run
/// concurrently; writes may not, nor a copy during a write.

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace rmap::slam2d {

template <class Cell>
class ChunkedGrid {
 public:
  /// Chunk edge is 2^kChunkBits cells (64).
  static constexpr int kChunkBits = 6;
  static constexpr int kChunkEdge = 1 << kChunkBits;
  static constexpr int kChunkMask = kChunkEdge - 1;
  using Chunk = std::array<Cell, kChunkEdge * kChunkEdge>;

  /// Cell at integer indices, nullptr when its chunk was never written.
  const Cell* find(int x, int y) const {
    const Chunk* chunk = findChunk(x >> kChunkBits, y >> kChunkBits);
    return chunk ? &(*chunk)[offset(x, y)] : nullptr;
  }

  /// Cell at integer indices, allocating its chunk (cells default-constructed).
  Cell& at(int x, int y) { return (*chunkAt(x >> kChunkBits, y >> kChunkBits))[offset(x, y)]; }

  /// The chunk of the last cell reached through it: a walk over neighbouring cells (a ray)
  /// then mostly skips the hash table. Stays valid as chunks are added, not across a copy.
  struct Cursor {
    int cx = 0, cy = 0;
    Chunk* chunk = nullptr;
  };
  /// As at(x, y), through `cursor`.
  Cell& at(int x, int y, Cursor& cursor) {
    const int cx = x >> kChunkBits, cy = y >> kChunkBits;
    if (!cursor.chunk || cx != cursor.cx || cy != cursor.cy) cursor = {cx, cy, chunkAt(cx, cy)};
    return (*cursor.chunk)[offset(x, y)];
  }

  /// Number of allocated chunks.
  size_t chunkCount() const { return chunks_.size(); }
  /// Calls fn(const void*) with each chunk's address: copies that share a chunk give the same one.
  template <class Fn>
  void forEachChunk(Fn&& fn) const {
    for (const std::shared_ptr<Chunk>& chunk : chunks_) fn(static_cast<const void*>(chunk.get()));
  }

 private:
  struct Slot {
    uint64_t key = 0;
    int32_t index = -1;  ///< into chunks_, −1 = empty slot
  };

  static size_t offset(int x, int y) { return (static_cast<size_t>(y & kChunkMask) << kChunkBits) | (x & kChunkMask); }
  static uint64_t keyOf(int cx, int cy) {
    return (static_cast<uint64_t>(static_cast<uint32_t>(cx)) << 32) | static_cast<uint32_t>(cy);
  }
  size_t slotOf(uint64_t key) const { return static_cast<size_t>((key * 0x9E3779B97F4A7C15ull) >> shift_); }

  /// Index into chunks_, −1 when the chunk was never written.
  int32_t indexOf(int cx, int cy) const {
    if (table_.empty()) return -1;
    const uint64_t key = keyOf(cx, cy);
    const size_t mask = table_.size() - 1;
    for (size_t s = slotOf(key);; s = (s + 1) & mask) {
      const Slot& slot = table_[s];
      if (slot.index < 0 || slot.key == key) return slot.index;
    }
  }
  const Chunk* findChunk(int cx, int cy) const {
    const int32_t index = indexOf(cx, cy);
    return index < 0 ? nullptr : chunks_[static_cast<size_t>(index)].get();
  }

  /// A chunk this grid alone holds, ready for writing.
  Chunk* chunkAt(int cx, int cy) {
    const int32_t index = indexOf(cx, cy);
    if (index < 0) return insertChunk(cx, cy);
    std::shared_ptr<Chunk>& chunk = chunks_[static_cast<size_t>(index)];
    if (chunk.use_count() > 1) chunk = std::make_shared<Chunk>(*chunk);  // shared with a copy
    return chunk.get();
  }
  Chunk* insertChunk(int cx, int cy) {
    if (2 * (chunks_.size() + 1) > table_.size()) rehash(table_.empty() ? 64 : 2 * table_.size());
    chunks_.push_back(std::make_shared<Chunk>());
    place(keyOf(cx, cy), static_cast<int32_t>(chunks_.size() - 1));
    return chunks_.back().get();
  }

  void place(uint64_t key, int32_t index) {
    const size_t mask = table_.size() - 1;
    size_t s = slotOf(key);
    while (table_[s].index >= 0) s = (s + 1) & mask;
    table_[s] = {key, index};
  }

  void rehash(size_t capacity) {
    std::vector<Slot> old = std::move(table_);
    table_.assign(capacity, Slot{});
    shift_ = 64;
    for (size_t c = capacity; c > 1; c >>= 1) --shift_;
    for (const Slot& slot : old)
      if (slot.index >= 0) place(slot.key, slot.index);
  }

  std::vector<std::shared_ptr<Chunk>> chunks_;  ///< shared with copies until written
  std::vector<Slot> table_;  ///< capacity a power of two
  int shift_ = 64;           ///< 64 − log2(capacity): Fibonacci hashing takes the top bits
};

}  // namespace rmap::slam2d
