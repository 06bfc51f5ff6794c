#include "loop/inverted_index.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

namespace rmap::loop {
namespace {

std::map<int64_t, double> byFrame(const std::vector<FrameScore>& scores) {
  std::map<int64_t, double> out;
  for (const FrameScore& s : scores) out[s.frame] = s.score;
  return out;
}

TEST(InvertedIndex, ScoresAreIdfWeightedIntersectionsNormalisedByTheQuery) {
  InvertedIndex index;
  index.addFrame(std::vector<WordId>{0, 1, 2, 2});  // frame 0
  index.addFrame(std::vector<WordId>{0, 3});        // frame 1
  index.addFrame(std::vector<WordId>{4, 5});        // frame 2
  EXPECT_EQ(index.frames(), 3u);
  EXPECT_EQ(index.documentFrequency(0), 2u);
  EXPECT_EQ(index.count(2, 0), 2);
  EXPECT_EQ(index.count(2, 1), 0);

  const std::vector<WordId> query{0, 2, 6, -1};  // word 6 is new, -1 is skipped
  const auto s = byFrame(index.score(query, 3));
  const double idf0 = std::log(4.0 / 3.0), idf2 = std::log(4.0 / 2.0), idf6 = std::log(4.0 / 1.0);
  const double self = (idf0 + idf2 + idf6) / 3.0;
  ASSERT_EQ(s.size(), 2u);  // frame 2 shares nothing
  EXPECT_NEAR(s.at(0), (idf0 * std::min(1.0 / 3, 0.25) + idf2 * std::min(1.0 / 3, 0.5)) / self, 1e-12);
  EXPECT_NEAR(s.at(1), idf0 * std::min(1.0 / 3, 0.5) / self, 1e-12);

  // A frame identical to the query scores 1 once the query's words are all known.
  InvertedIndex same;
  same.addFrame(std::vector<WordId>{7, 8});
  same.addFrame(std::vector<WordId>{9});
  EXPECT_NEAR(byFrame(same.score(std::vector<WordId>{7, 8}, 2)).at(0), 1.0, 1e-12);
}

TEST(InvertedIndex, RecentFramesAreExcluded) {
  InvertedIndex index;
  for (int f = 0; f < 5; ++f) index.addFrame(std::vector<WordId>{1, 2});
  index.addFrame(std::vector<WordId>{3});
  const auto s = byFrame(index.score(std::vector<WordId>{1}, 3));
  EXPECT_EQ(s.size(), 3u);
  EXPECT_EQ(s.count(3), 0u);
  EXPECT_TRUE(index.score(std::vector<WordId>{1}, 0).empty());
  EXPECT_TRUE(index.score(std::vector<WordId>{}, 6).empty());
}

TEST(InvertedIndex, MergedWordsPoolTheirPostings) {
  InvertedIndex index;
  index.addFrame(std::vector<WordId>{1});     // 0
  index.addFrame(std::vector<WordId>{2});     // 1
  index.addFrame(std::vector<WordId>{1, 2});  // 2
  index.mergeWords(1, 2);
  EXPECT_EQ(index.documentFrequency(1), 3u);
  EXPECT_EQ(index.documentFrequency(2), 0u);
  EXPECT_EQ(index.count(1, 1), 1);
  EXPECT_EQ(index.count(1, 2), 2);
  index.removeWord(1);
  EXPECT_EQ(index.documentFrequency(1), 0u);
  EXPECT_TRUE(index.score(std::vector<WordId>{1}, 3).empty());
}

}  // namespace
}  // namespace rmap::loop
