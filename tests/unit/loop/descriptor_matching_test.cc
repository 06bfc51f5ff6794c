#include "loop/descriptor_matching.h"

#include <gtest/gtest.h>

#include <bit>
#include <climits>
#include <random>
#include <vector>

namespace rmap::loop {
namespace {

int distance(const cv::Mat& a, int i, const cv::Mat& b, int j) {
  int d = 0;
  for (int c = 0; c < a.cols; ++c) d += std::popcount(static_cast<unsigned>(a.at<uint8_t>(i, c) ^ b.at<uint8_t>(j, c)));
  return d;
}

/// The definition, pair by pair: i's nearest j (first on ties) within max_bits,
/// j's nearest i (first on ties) is i, and nearest < ratio · second nearest of i.
std::vector<std::pair<int, int>> byDefinition(const cv::Mat& a, const cv::Mat& b, int max_bits, double ratio) {
  std::vector<std::pair<int, int>> out;
  for (int i = 0; i < a.rows; ++i) {
    int best = -1, first = INT_MAX, second = INT_MAX;
    for (int j = 0; j < b.rows; ++j) {
      const int d = distance(a, i, b, j);
      if (d < first) second = first, first = d, best = j;
      else if (d < second) second = d;
    }
    if (best < 0 || first > max_bits) continue;
    int back = -1, back_d = INT_MAX;
    for (int k = 0; k < a.rows; ++k)
      if (const int d = distance(a, k, b, best); d < back_d) back_d = d, back = k;
    if (back != i || (second != INT_MAX && first >= ratio * second)) continue;
    out.emplace_back(i, best);
  }
  return out;
}

/// Rows of `bytes` bytes: random, near copies of each other, and exact duplicates (ties).
cv::Mat descriptors(std::mt19937& rng, int rows, int bytes, const cv::Mat& like = cv::Mat()) {
  cv::Mat m(rows, bytes, CV_8U);
  for (int i = 0; i < rows; ++i)
    for (int c = 0; c < bytes; ++c) {
      uint8_t v = static_cast<uint8_t>(rng());
      if (!like.empty() && rng() % 3 != 0) v = like.at<uint8_t>(static_cast<int>(rng() % like.rows), c) ^ (rng() % 8 == 0 ? 1 : 0);
      if (rng() % 4 == 0) v = static_cast<uint8_t>(rng() % 2);
      m.at<uint8_t>(i, c) = v;
    }
  return m;
}

TEST(MutualMatches, EqualTheDefinitionForEveryWidthAndSize) {
  std::mt19937 rng(3);
  for (int bytes : {32, 61, 64})
    for (int rows : {1, 7, 8, 9, 23, 64}) {
      const cv::Mat a = descriptors(rng, rows, bytes);
      const cv::Mat b = descriptors(rng, rows + 3, bytes, a);
      for (const auto& [max_bits, ratio] : {std::pair{bytes * 8, 1.0}, {bytes * 2, 0.8}}) {
        EXPECT_EQ(mutualMatches(a, b, max_bits, ratio), byDefinition(a, b, max_bits, ratio))
            << bytes << " bytes, " << rows << " rows, max " << max_bits << " ratio " << ratio;
      }
    }
}

TEST(MutualMatches, EmptySetsMatchNothing) {
  const cv::Mat none(0, 32, CV_8U), one(1, 32, CV_8U, cv::Scalar(7));
  EXPECT_TRUE(mutualMatches(none, one, 256, 1.0).empty());
  EXPECT_TRUE(mutualMatches(one, none, 256, 1.0).empty());
  EXPECT_EQ(mutualMatches(one, one, 256, 1.0), (std::vector<std::pair<int, int>>{{0, 0}}));
}

}  // namespace
}  // namespace rmap::loop
