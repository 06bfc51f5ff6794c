#include "map3d/block_index.h"

#include <gtest/gtest.h>

#include <random>
#include <unordered_map>

namespace rmap::map3d {
namespace {

TEST(BlockIndex, FindsEveryInsertedKeyAcrossGrowth) {
  BlockIndex index;
  std::unordered_map<BlockKey, uint32_t, BlockKeyHash> reference;
  std::mt19937 rng(1);
  std::uniform_int_distribution<int32_t> coord(-2048, 2047);
  while (reference.size() < 5000) {
    const BlockKey key{coord(rng), coord(rng), coord(rng) / 64};
    if (reference.count(key)) continue;
    const auto value = static_cast<uint32_t>(reference.size());
    reference[key] = value;
    index.insert(key, value);
  }
  EXPECT_EQ(index.size(), reference.size());
  for (const auto& [key, value] : reference) ASSERT_EQ(index.find(key), value);
  EXPECT_EQ(index.find({5000, 5000, 5000}), BlockIndex::kMissing);
}

TEST(BlockIndex, EmptyIndexFindsNothing) {
  const BlockIndex index;
  EXPECT_EQ(index.find({0, 0, 0}), BlockIndex::kMissing);
  EXPECT_EQ(index.size(), 0u);
}

TEST(BlockIndex, NeighbouringKeysDoNotCollide) {
  BlockIndex index;
  uint32_t n = 0;
  for (int32_t z = -3; z <= 3; ++z)
    for (int32_t y = -3; y <= 3; ++y)
      for (int32_t x = -3; x <= 3; ++x) index.insert({x, y, z}, n++);
  n = 0;
  for (int32_t z = -3; z <= 3; ++z)
    for (int32_t y = -3; y <= 3; ++y)
      for (int32_t x = -3; x <= 3; ++x) ASSERT_EQ(index.find({x, y, z}), n++);
}

}  // namespace
}  // namespace rmap::map3d
