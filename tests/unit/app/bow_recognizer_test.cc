#include "app/bow_recognizer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "slam2d/loop_closure.h"

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

/// A point image for texture(seed): a wall whose depth varies with the pixel and the seed, metres.
cv::Mat wall(int seed) {
  cv::Mat points(240, 320, CV_32FC3);
  for (int v = 0; v < points.rows; ++v) {
    for (int u = 0; u < points.cols; ++u) {
      const float depth = 5.0f + std::sin(0.02f * u + seed) + 0.5f * std::cos(0.03f * v + seed);
      points.at<cv::Vec3f>(v, u) = cv::Vec3f(depth, 0.02f * (160 - u), 0.02f * (120 - v));
    }
  }
  return points;
}

TEST(BowRecognizer, PanoramasAreVerifiedInMetresAndTheMatchCarriesTheMeasuredPose) {
  const std::unique_ptr<PlaceRecognizer> panoramas = bowRecognizers(LoopClosureConfig{})(FrameKind::kIntensityPanorama);
  ASSERT_NE(panoramas, nullptr);
  EXPECT_THROW(panoramas->addFrame(texture(0), "r1"), std::invalid_argument);  // no points
  constexpr int kPlaces = 60;
  for (int i = 0; i < kPlaces; ++i) EXPECT_FALSE(panoramas->addFrame(PlaceImage(texture(i), wall(i)), "r1"));
  // The sensor is back at places 0, 1, 2, … 0.4 m further along x: every point 0.4 m nearer.
  std::optional<PlaceRecognizer::Match> match;
  for (int i = 0; i < 5 && !match; ++i) {
    cv::Mat nearer = wall(i) - cv::Scalar(0.4f, 0.0f, 0.0f);
    match = panoramas->addFrame(PlaceImage(texture(i), nearer), "r1");
  }
  ASSERT_TRUE(match);
  EXPECT_LE(match->reference_frame, 4);
  ASSERT_TRUE(match->reference_from_query);
  // The new sensor pose in the old sensor frame: 0.4 m forward.
  EXPECT_NEAR(match->reference_from_query->translation().x(), 0.4, 0.05);
  EXPECT_NEAR(match->reference_from_query->translation().y(), 0.0, 0.05);
}

TEST(BowRecognizer, PatchClosuresCarryTheRobotsMotionBetweenThePatchCentres) {
  const std::unique_ptr<PlaceRecognizer> patches = bowRecognizers(LoopClosureConfig{})(FrameKind::kReflectivityPatch);
  ASSERT_NE(patches, nullptr);
  // Patches as rmapd cuts them (160 × 160 px of 5 cm); each place its own.
  const auto patch = [](int seed) { return texture(seed)(cv::Rect(0, 0, 160, 160)).clone(); };
  constexpr int kPlaces = 60;
  for (int i = 0; i < kPlaces; ++i) EXPECT_FALSE(patches->addFrame(patch(i), "r1"));
  // Back at places 0, 1, 2, … 0.5 m to the left: the patch's content lies 10 columns further right.
  std::optional<PlaceRecognizer::Match> match;
  for (int i = 0; i < 5 && !match; ++i) {
    cv::Mat moved;
    cv::warpAffine(patch(i), moved, cv::Matx23d(1, 0, 10, 0, 1, 0), cv::Size(160, 160));
    match = patches->addFrame(moved, "r1");
  }
  ASSERT_TRUE(match);
  ASSERT_TRUE(match->reference_from_query);
  EXPECT_NEAR(match->reference_from_query->translation().x(), 0.0, 0.03);
  EXPECT_NEAR(match->reference_from_query->translation().y(), 0.5, 0.03);
  EXPECT_LT(Eigen::AngleAxisd(match->reference_from_query->linear()).angle(), 0.01);
  // Patches are cut around the 2D SLAM's poses: a measured pose must agree with them within the
  // SLAM's widest loop search. Panoramas' poses are the robots' own: not checked.
  ASSERT_TRUE(patches->measuredPoseTolerance());
  EXPECT_EQ(patches->measuredPoseTolerance()->translation_m, slam2d::LoopClosureOptions{}.max_window_m);
  EXPECT_EQ(patches->measuredPoseTolerance()->rotation_rad, slam2d::LoopClosureOptions{}.max_window_rad);
  EXPECT_FALSE(bowRecognizers(LoopClosureConfig{})(FrameKind::kIntensityPanorama)->measuredPoseTolerance());
}

}  // namespace
}  // namespace rmap::app
