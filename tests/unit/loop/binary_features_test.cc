#include "loop/binary_features.h"

#include <gtest/gtest.h>

#include "test_images.h"

namespace rmap::loop {
namespace {

TEST(BinaryFeatures, EveryDescriptorTypeDescribesItsKeypointsUpToTheCap) {
  const cv::Mat img = test::texturedScene(1);
  for (DescriptorType t : {DescriptorType::kOrb, DescriptorType::kBrisk, DescriptorType::kAkaze}) {
    SCOPED_TRACE(toString(t));
    auto ex = makeExtractor(t, 200);
    EXPECT_EQ(ex->type(), t);
    const Features f = ex->extract(img);
    EXPECT_GT(f.keypoints.size(), 50u);
    EXPECT_LE(f.keypoints.size(), 200u);
    EXPECT_EQ(f.descriptors.rows, static_cast<int>(f.keypoints.size()));
    EXPECT_EQ(f.descriptors.type(), CV_8UC1);
    EXPECT_EQ(f.descriptors.cols, ex->descriptorBytes());
  }
  EXPECT_EQ(makeExtractor(DescriptorType::kOrb)->descriptorBytes(), 32);
  EXPECT_EQ(makeExtractor(DescriptorType::kBrisk)->descriptorBytes(), 64);
  EXPECT_EQ(makeExtractor(DescriptorType::kAkaze)->descriptorBytes(), 61);
}

TEST(BinaryFeatures, OrbCoversSmallImagesToTheBorderMargin) {
  // 240×192: the keypoints spread over the image, not only its centre.
  const Features f = makeExtractor()->extract(test::texturedScene(2, 240, 192));
  float min_x = 1e9f, max_x = 0.0f;
  for (const cv::KeyPoint& k : f.keypoints) min_x = std::min(min_x, k.pt.x), max_x = std::max(max_x, k.pt.x);
  EXPECT_LT(min_x, 25.0f);
  EXPECT_GT(max_x, 215.0f);
}

TEST(BinaryFeatures, BadImagesThrow) {
  auto ex = makeExtractor();
  EXPECT_THROW(ex->extract(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(ex->extract(cv::Mat(64, 64, CV_8UC3, cv::Scalar::all(0))), std::invalid_argument);
  EXPECT_THROW(ex->extract(cv::Mat(64, 64, CV_16UC1, cv::Scalar::all(0))), std::invalid_argument);
  EXPECT_THROW(checkGrayImage(cv::Mat(20, 64, CV_8UC1), 32), std::invalid_argument);
  EXPECT_NO_THROW(checkGrayImage(cv::Mat(32, 32, CV_8UC1), 32));
  // A blank image is valid and has no features.
  const Features f = ex->extract(cv::Mat(64, 64, CV_8UC1, cv::Scalar::all(128)));
  EXPECT_TRUE(f.keypoints.empty());
}

TEST(BinaryFeatures, OptionsAndNamesAreValidated) {
  ExtractorOptions o;
  EXPECT_NO_THROW(o.validate());
  o.max_features = 0;
  EXPECT_THROW(makeExtractor(DescriptorType::kOrb, o), std::invalid_argument);
  o = {};
  o.scale_factor = 1.0;
  EXPECT_THROW(o.validate(), std::invalid_argument);
  o = {};
  o.edge_threshold_px = 1;
  EXPECT_THROW(o.validate(), std::invalid_argument);
  EXPECT_EQ(descriptorTypeFromString("akaze"), DescriptorType::kAkaze);
  EXPECT_THROW(descriptorTypeFromString("sift"), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::loop
