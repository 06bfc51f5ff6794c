#include "app/bow_recognizer.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

namespace rmap::app {
namespace {

/// A textured image of its own for each seed: blurred random blocks (corners for ORB).
cv::Mat texture(int seed) {
  cv::Mat image(240, 320, CV_8UC1);
  cv::RNG rng(static_cast<uint64_t>(seed) + 1);
  for (int y = 0; y < image.rows; y += 8) {
    for (int x = 0; x < image.cols; x += 8) {
      image(cv::Rect(x, y, 8, 8)).setTo(cv::Scalar(rng.uniform(0, 256)));
    }
  }
  cv::GaussianBlur(image, image, cv::Size(3, 3), 0);
  return image;
}

TEST(BowRecognizer, ARevisitedPlaceMatchesItsFirstVisitAndNewPlacesDoNot) {
  BowRecognizer recognizer;
  constexpr int kPlaces = 60;  // more than the detector's window of recent frames
  for (int i = 0; i < kPlaces; ++i) EXPECT_FALSE(recognizer.addFrame(texture(i), "r1")) << "frame " << i;
  std::optional<PlaceRecognizer::Match> match;
  for (int i = 0; i < 3 && !match; ++i) match = recognizer.addFrame(texture(i), "r1");
  ASSERT_TRUE(match);
  EXPECT_LE(match->reference_frame, 2);
  EXPECT_GT(match->score, 0.0);
}

TEST(BowRecognizer, TheConfigTurnsKindsOff) {
  LoopClosureConfig config;
  config.camera = false;
  const RecognizerFactory factory = bowRecognizers(config);
  EXPECT_EQ(factory(FrameKind::kCamera), nullptr);
  EXPECT_NE(factory(FrameKind::kIntensityPanorama), nullptr);
  EXPECT_NE(factory(FrameKind::kReflectivityPatch), nullptr);
}

TEST(BowRecognizer, PanoramasAreVerifiedInMetresSoTheyNeedTheirPoints) {
  const std::unique_ptr<PlaceRecognizer> panoramas = bowRecognizers(LoopClosureConfig{})(FrameKind::kIntensityPanorama);
  ASSERT_NE(panoramas, nullptr);
  EXPECT_THROW(panoramas->addFrame(texture(0), "r1"), std::invalid_argument);
  const cv::Mat points(240, 320, CV_32FC3, cv::Scalar(3.0f, 1.0f, 0.5f));
  EXPECT_NO_THROW(panoramas->addFrame(PlaceImage(texture(0), points), "r1"));
}

}  // namespace
}  // namespace rmap::app
