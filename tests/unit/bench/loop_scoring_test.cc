#include "loop/loop_scoring.h"

#include <gtest/gtest.h>

#include <sstream>

namespace rmap::bench {
namespace {

LoopGroundTruth truthOf(const std::string& text) {
  std::istringstream in(text);
  return parseLoopGroundTruth(in);
}

TEST(LoopScoring, ParsesPairsCommentsAndBlankLines) {
  const LoopGroundTruth t = truthOf("# header\n10 1\n10 2  # trailing\n\n  \n12 4\n");
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t.at(10), (std::set<int64_t>{1, 2}));
  EXPECT_EQ(t.at(12), (std::set<int64_t>{4}));
}

TEST(LoopScoring, MalformedLinesThrowWithTheLineNumber) {
  try {
    truthOf("10 1\n11\n");
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(truthOf("10 1 3\n"), std::runtime_error);
  EXPECT_THROW(truthOf("10 -1\n"), std::runtime_error);
  EXPECT_THROW(truthOf("x y\n"), std::runtime_error);
  EXPECT_THROW(readLoopGroundTruth("/nonexistent/pairs.txt"), std::runtime_error);
}

TEST(LoopScoring, ToleranceWidensTheTrueReferences) {
  const LoopGroundTruth t = truthOf("100 10\n100 11\n");
  EXPECT_TRUE(isCorrect(t, 100, 10, 0));
  EXPECT_FALSE(isCorrect(t, 100, 12, 0));
  EXPECT_TRUE(isCorrect(t, 100, 13, 2));
  EXPECT_FALSE(isCorrect(t, 100, 14, 2));
  EXPECT_TRUE(isCorrect(t, 100, 8, 2));
  EXPECT_FALSE(isCorrect(t, 100, 7, 2));
  EXPECT_FALSE(isCorrect(t, 101, 10, 40));  // not a loop query
}

TEST(LoopScoring, CurveSweepsTheScoreAndReadsRecallAtFullPrecision) {
  // Four loop queries (100..103); the detector declares five loops.
  const LoopGroundTruth t = truthOf("100 10\n101 11\n102 12\n103 13\n");
  const std::vector<LoopDeclaration> d = {
      {100, 10, 0.9},  // correct
      {101, 11, 0.8},  // correct
      {50, 5, 0.7},    // false: 50 is no loop query
      {102, 15, 0.6},  // correct only with tolerance >= 3
      {103, 13, 0.6},  // correct
  };
  const PrCurve c0 = precisionRecallCurve(d, t, 0);
  EXPECT_EQ(c0.loop_queries, 4u);
  ASSERT_EQ(c0.points.size(), 4u);  // 0.9, 0.8, 0.7, 0.6 (tied pair is one point)
  EXPECT_DOUBLE_EQ(c0.points[1].precision, 1.0);
  EXPECT_DOUBLE_EQ(c0.points[1].recall, 0.5);
  EXPECT_DOUBLE_EQ(c0.points[2].precision, 2.0 / 3.0);
  EXPECT_EQ(c0.points[3].declared, 5u);
  EXPECT_EQ(c0.points[3].correct, 3u);
  EXPECT_DOUBLE_EQ(c0.points[3].recall, 0.75);
  EXPECT_DOUBLE_EQ(c0.recall_at_100_precision, 0.5);
  // AUC: 0.25·1 + 0.25·1 + 0·(2/3) + 0.25·0.6
  EXPECT_NEAR(c0.auc, 0.5 + 0.25 * 0.6, 1e-12);

  const PrCurve c3 = precisionRecallCurve(d, t, 3);
  EXPECT_DOUBLE_EQ(c3.points.back().recall, 1.0);
  EXPECT_DOUBLE_EQ(c3.recall_at_100_precision, 0.5);  // the false 0.7 caps it

  const PrCurve none = precisionRecallCurve({{50, 5, 0.9}, {100, 10, 0.5}}, t, 40);
  EXPECT_DOUBLE_EQ(none.recall_at_100_precision, 0.0);
}

TEST(LoopScoring, OnlyTheBestDeclarationOfAQueryCounts) {
  const LoopGroundTruth t = truthOf("100 10\n");
  const PrPoint p = precisionRecall({{100, 60, 0.3}, {100, 10, 0.9}}, t, 0);
  EXPECT_EQ(p.declared, 1u);
  EXPECT_EQ(p.correct, 1u);
  EXPECT_DOUBLE_EQ(p.precision, 1.0);
  EXPECT_DOUBLE_EQ(p.recall, 1.0);
  const PrPoint empty = precisionRecall({}, t, 0);
  EXPECT_DOUBLE_EQ(empty.precision, 1.0);
  EXPECT_DOUBLE_EQ(empty.recall, 0.0);
}

TEST(LoopScoring, TruncationKeepsQueriesBelowTheFrameCount) {
  const LoopGroundTruth t = truncateGroundTruth(truthOf("5 1\n9 2\n10 3\n"), 10);
  EXPECT_EQ(t.size(), 2u);
  EXPECT_EQ(t.count(10), 0u);
}

}  // namespace
}  // namespace rmap::bench
