#include "slam2d/chunked_grid.h"

#include <gtest/gtest.h>

#include <utility>
#include <vector>

namespace rmap::slam2d {
namespace {

TEST(ChunkedGrid, ReadsNothingBeforeAWrite) {
  ChunkedGrid<int> grid;
  EXPECT_EQ(grid.find(0, 0), nullptr);
  EXPECT_EQ(grid.find(-100000, 7), nullptr);
  EXPECT_EQ(grid.chunkCount(), 0u);
}

TEST(ChunkedGrid, GrowsInEveryDirectionAndKeepsCellsInPlace) {
  ChunkedGrid<int> grid;
  grid.at(0, 0) = 1;
  int* first = &grid.at(0, 0);
  // Far in all four directions and the diagonals, negative indices included.
  const int far = 1 << 20;
  const int xs[] = {far, -far, 0, 0, far, -far, 63, 64, -1, -64, -65};
  const int ys[] = {0, 0, far, -far, -far, far, 63, 64, -1, -64, -65};
  for (int k = 0; k < 11; ++k) grid.at(xs[k], ys[k]) = k + 10;
  // Many chunks force rehashing; earlier cells must survive it.
  for (int k = 0; k < 500; ++k) grid.at(k * 64, -k * 64) += 1;
  EXPECT_EQ(&grid.at(0, 0), first);
  EXPECT_EQ(*grid.find(0, 0), 2);  // 1, then +1 from k = 0
  for (int k = 1; k < 11; ++k) EXPECT_EQ(*grid.find(xs[k], ys[k]), k + 10) << k;
  EXPECT_EQ(*grid.find(64 * 499, -64 * 499), 1);
  // Neighbours of written cells in the same chunk exist and are default; other chunks do not.
  ASSERT_NE(grid.find(1, 1), nullptr);
  EXPECT_EQ(*grid.find(1, 1), 0);
  EXPECT_EQ(grid.find(far / 2, far / 2), nullptr);
  // -1 and -64 share chunk -1; -65 is in chunk -2.
  EXPECT_NE(grid.find(-33, -33), nullptr);
}

TEST(ChunkedGrid, ACursorReachesTheSameCellsAsDirectAccessAcrossChunks) {
  ChunkedGrid<int> grid;
  ChunkedGrid<int>::Cursor cursor;
  // A walk through four chunks around the origin and back, and a jump far away and back.
  std::vector<std::pair<int, int>> walk;
  for (int k = -70; k <= 70; ++k) walk.emplace_back(k, k / 2);
  for (int k = 70; k >= -70; k -= 7) walk.emplace_back(k, -k);
  walk.emplace_back(1 << 20, -(1 << 20));
  walk.emplace_back(0, 0);
  int written = 0;
  for (const auto& [x, y] : walk) grid.at(x, y, cursor) += ++written;
  ChunkedGrid<int> direct;
  written = 0;
  for (const auto& [x, y] : walk) direct.at(x, y) += ++written;
  EXPECT_EQ(grid.chunkCount(), direct.chunkCount());
  for (const auto& [x, y] : walk) {
    ASSERT_NE(grid.find(x, y), nullptr);
    EXPECT_EQ(*grid.find(x, y), *direct.find(x, y)) << x << ", " << y;
    EXPECT_EQ(&grid.at(x, y, cursor), grid.find(x, y));
  }
}

TEST(ChunkedGrid, ACopySharesChunksUntilEitherSideWritesThem) {
  ChunkedGrid<int> original;
  for (int k = 0; k < 200; ++k) original.at(k, -k) = k;  // four chunks
  ChunkedGrid<int> copy = original;
  EXPECT_EQ(copy.find(5, -5), original.find(5, -5)) << "a copy shares the chunks";
  // Writes through a cursor and directly, on both sides: the other side keeps its values.
  ChunkedGrid<int>::Cursor cursor;
  copy.at(5, -5, cursor) = -1;
  copy.at(6, -6, cursor) = -2;
  original.at(150, -150) = -3;
  copy.at(1000, 1000) = 7;  // a chunk only the copy has
  EXPECT_EQ(*original.find(5, -5), 5);
  EXPECT_EQ(*original.find(6, -6), 6);
  EXPECT_EQ(*copy.find(5, -5), -1);
  EXPECT_EQ(*copy.find(6, -6), -2);
  EXPECT_EQ(*copy.find(150, -150), 150);
  EXPECT_EQ(*original.find(150, -150), -3);
  EXPECT_EQ(original.find(1000, 1000), nullptr);
  // A chunk neither side wrote is still shared; a written one is not.
  EXPECT_EQ(copy.find(100, -100), original.find(100, -100));
  EXPECT_NE(copy.find(5, -5), original.find(5, -5));
  EXPECT_EQ(copy.chunkCount(), original.chunkCount() + 1);
}

}  // namespace
}  // namespace rmap::slam2d
