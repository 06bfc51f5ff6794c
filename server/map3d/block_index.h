#pragma once
/// @file block_index.h
/// Open-addressing map from block keys to small indices, for the per-scan
/// marks: a walk looks a block up each time it crosses into one, and
/// std::unordered_map's node chasing cost ~10 % of the walk. (Boost 1.74 of
/// Debian 12 predates boost::unordered_flat_map.)

#include <cstdint>
#include <vector>

#include "map3d/cell_key.h"

namespace rmap::map3d {

class BlockIndex {
 public:
  static constexpr uint32_t kMissing = UINT32_MAX;

  /// Index stored for `key`, or kMissing.
  uint32_t find(const BlockKey& key) const {
    if (slots_.empty()) return kMissing;
    for (size_t i = slotOf(key);; i = (i + 1) & mask_) {
      if (slots_[i].value == kMissing || slots_[i].key == key) return slots_[i].value;
    }
  }

  /// Stores `value` (not kMissing) for a key that is not present yet.
  void insert(const BlockKey& key, uint32_t value) {
    if (2 * (size_ + 1) > slots_.size()) grow();
    size_t i = slotOf(key);
    while (slots_[i].value != kMissing) i = (i + 1) & mask_;
    slots_[i] = {key, value};
    ++size_;
  }

  size_t size() const { return size_; }

 private:
  struct Slot {
    BlockKey key;
    uint32_t value = kMissing;
  };

  size_t slotOf(const BlockKey& key) const { return BlockKeyHash{}(key) & mask_; }

  void grow() {
    std::vector<Slot> old = std::move(slots_);
    slots_.assign(old.empty() ? 256 : 2 * old.size(), Slot{});
    mask_ = slots_.size() - 1;
    size_ = 0;
    for (const Slot& s : old) {
      if (s.value != kMissing) insert(s.key, s.value);
    }
  }

  std::vector<Slot> slots_;
  size_t mask_ = 0;
  size_t size_ = 0;
};

}  // namespace rmap::map3d
