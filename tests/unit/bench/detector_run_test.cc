#include "loop_sim/detector_run.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

namespace rmap::bench {
namespace {

TEST(DetectorRun, QuantileIsNearestRank) {
  EXPECT_EQ(quantileOf({}, 0.5), 0.0);
  EXPECT_EQ(quantileOf({5, 1, 4, 2, 3}, 0.0), 1.0);
  EXPECT_EQ(quantileOf({5, 1, 4, 2, 3}, 0.5), 3.0);
  EXPECT_EQ(quantileOf({5, 1, 4, 2, 3}, 0.95), 5.0);
  EXPECT_EQ(quantileOf({5, 1, 4, 2, 3}, 1.0), 5.0);
  EXPECT_DOUBLE_EQ(meanOf({1, 2, 6}), 3.0);
}

TEST(DetectorRun, TimesEveryFrameAndScoresTheDeclarations) {
  cv::RNG rng(3);
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 8; ++i) {
    cv::Mat m(96, 128, CV_8UC1);
    rng.fill(m, cv::RNG::UNIFORM, 0, 256);
    frames.push_back(m);
  }
  const DetectorRun run = runDetector([&](size_t i) { return frames[i]; }, frames.size(), loop::DescriptorType::kOrb);
  EXPECT_EQ(run.wall_ms.size(), 8u);
  EXPECT_EQ(run.cpu_ms.size(), 8u);
  EXPECT_GT(run.vocabulary_words, 0u);
  EXPECT_TRUE(run.accepted.empty());  // 8 frames: all inside the exclusion window
  const LoopGroundTruth truth{{7, {1}}};
  const nlohmann::json j = scoreJson(run, truth, {0, 2});
  EXPECT_EQ(j["loop_queries"], 1);
  EXPECT_EQ(j["recall"]["tol2"], 0.0);
  EXPECT_EQ(j["precision"]["tol0"], 1.0);  // nothing declared
}

}  // namespace
}  // namespace rmap::bench
