#pragma once
/// @file binary_descriptor.h
/// Binary descriptors packed into 64-bit blocks (zero-padded), and their
/// Hamming distance by popcount.

#include <bit>
#include <cstdint>
#include <cstring>
#include <vector>

namespace rmap::loop {

/// 64-bit blocks holding `bytes` descriptor bytes.
constexpr int descriptorBlocks(int bytes) { return (bytes + 7) / 8; }

/// Copies one descriptor row (`bytes` bytes) into `blocks` zero-padded 64-bit blocks at `out`.
inline void packDescriptor(const uint8_t* row, int bytes, uint64_t* out) {
  const int blocks = descriptorBlocks(bytes);
  for (int b = 0; b < blocks; ++b) out[b] = 0;
  std::memcpy(out, row, static_cast<size_t>(bytes));
}

/// Bits that differ between two packed descriptors of `blocks` blocks.
inline int hammingDistance(const uint64_t* a, const uint64_t* b, int blocks) {
  if (blocks == 4) {  // ORB: the common case, unrolled
    return std::popcount(a[0] ^ b[0]) + std::popcount(a[1] ^ b[1]) + std::popcount(a[2] ^ b[2]) +
           std::popcount(a[3] ^ b[3]);
  }
  int d = 0;
  for (int i = 0; i < blocks; ++i) d += std::popcount(a[i] ^ b[i]);
  return d;
}

inline bool testBit(const uint64_t* d, int bit) { return (d[bit >> 6] >> (bit & 63)) & 1u; }

}  // namespace rmap::loop
