#pragma once
/// @file dense_cells.h
/// The expanded ("hot") form of a block: one float log-odds per cell and a
/// bit per cell telling whether it was ever observed.

#include <array>
#include <bit>
#include <cstdint>

#include "map3d/cell_key.h"

namespace rmap::map3d {

inline constexpr int kBlockWords = kBlockCells / 64;

/// A bit per cell of a block.
struct BlockBits {
  std::array<uint64_t, kBlockWords> words{};

  void set(int i) { words[i >> 6] |= uint64_t{1} << (i & 63); }
  void reset(int i) { words[i >> 6] &= ~(uint64_t{1} << (i & 63)); }
  bool test(int i) const { return (words[i >> 6] >> (i & 63)) & 1u; }
  bool any() const {
    for (uint64_t w : words) {
      if (w) return true;
    }
    return false;
  }
  int count() const {
    int n = 0;
    for (uint64_t w : words) n += std::popcount(w);
    return n;
  }
  /// Calls fn(index) for every set bit, in increasing index order.
  template <class Fn>
  void forEach(Fn&& fn) const {
    for (int w = 0; w < kBlockWords; ++w) {
      uint64_t bits = words[w];
      while (bits) {
        fn((w << 6) | std::countr_zero(bits));
        bits &= bits - 1;
      }
    }
  }
};

struct DenseCells {
  std::array<float, kBlockCells> log_odds;  ///< meaningful where `known` is set; left uninitialised otherwise
  BlockBits known;
};

}  // namespace rmap::map3d
