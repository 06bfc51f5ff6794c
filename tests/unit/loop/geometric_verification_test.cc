#include "loop/geometric_verification.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "loop/binary_features.h"
#include "loop/descriptor_matching.h"
#include "test_images.h"

namespace rmap::loop {
namespace {

std::vector<cv::Point2f> points(const Features& f) {
  std::vector<cv::Point2f> p;
  for (const cv::KeyPoint& k : f.keypoints) p.push_back(k.pt);
  return p;
}

TEST(GeometricVerification, SameSceneHasManyInliersAndAnotherSceneFew) {
  auto ex = makeExtractor();
  const cv::Mat scene = test::texturedScene(11);
  const Features a = ex->extract(scene);
  const Features moved = ex->extract(test::shifted(scene, 6.0, -3.0));
  const Features other = ex->extract(test::texturedScene(12));
  const GeometricVerificationOptions o;
  const Verification same = verifyGeometry(points(a), a.descriptors, points(moved), moved.descriptors, o);
  const Verification different = verifyGeometry(points(a), a.descriptors, points(other), other.descriptors, o);
  EXPECT_GT(same.inliers, 100);
  EXPECT_LE(same.inliers, same.matches);
  EXPECT_LT(different.inliers, 12);
}

/// `img` turned by `angle_deg` about its centre and scaled by `scale` (same size, black outside).
cv::Mat turned(const cv::Mat& img, double angle_deg, double scale) {
  cv::Mat out;
  const cv::Mat m = cv::getRotationMatrix2D(cv::Point2f(img.cols / 2.0f, img.rows / 2.0f), angle_deg, scale);
  cv::warpAffine(img, out, m, img.size());
  return out;
}

TEST(GeometricVerification, ARigidFitTakesATurnedPictureButNotARescaledOne) {
  auto ex = makeExtractor();
  const cv::Mat scene = test::texturedScene(11);
  const Features a = ex->extract(scene);
  const Features turned_view = ex->extract(turned(test::shifted(scene, 6.0, -3.0), 25.0, 1.0));
  const Features zoomed_view = ex->extract(turned(scene, 0.0, 1.3));
  GeometricVerificationOptions rigid;
  rigid.model = GeometricModel::kRigid2d;
  const Verification same = verifyGeometry(points(a), a.descriptors, points(turned_view), turned_view.descriptors, rigid);
  EXPECT_GT(same.inliers, 50);
  // A zoom fits a fundamental matrix (it sees one plane) but is no rigid motion.
  const GeometricVerificationOptions fundamental;
  EXPECT_GT(verifyGeometry(points(a), a.descriptors, points(zoomed_view), zoomed_view.descriptors, fundamental).inliers,
            20);
  const Verification zoomed =
      verifyGeometry(points(a), a.descriptors, points(zoomed_view), zoomed_view.descriptors, rigid);
  EXPECT_GE(zoomed.matches, 15);
  EXPECT_EQ(zoomed.inliers, 0);
  GeometricVerificationOptions bad = rigid;
  bad.max_scale_error = 1.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(GeometricVerification, TooFewMatchesGiveNoInliersAndBadInputThrows) {
  const GeometricVerificationOptions o;
  const cv::Mat d(5, 32, CV_8U, cv::Scalar::all(7));
  const std::vector<cv::Point2f> p(5, cv::Point2f(1, 1));
  const Verification v = verifyGeometry(p, d, p, d, o);
  EXPECT_EQ(v.inliers, 0);
  EXPECT_THROW(verifyGeometry(p, d, std::vector<cv::Point2f>(4), d, o), std::invalid_argument);
  EXPECT_THROW(verifyGeometry(p, d, p, cv::Mat(5, 64, CV_8U), o), std::invalid_argument);
  GeometricVerificationOptions bad;
  bad.min_matches = 7;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = {};
  bad.ratio = 0.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(DescriptorMatching, MutualNearestPairsPassTheRatioAndDistanceTests) {
  cv::Mat a(3, 32, CV_8U, cv::Scalar::all(0)), b(3, 32, CV_8U, cv::Scalar::all(0));
  a.row(0).setTo(0x00);
  a.row(1).setTo(0xFF);
  a.row(2).setTo(0x0F);
  b.row(0).setTo(0xFF);  // = a1
  b.row(1).setTo(0x01);  // 32 bits from a0
  b.row(2).setTo(0x3F);  // 64 bits from a2, 64 from a1
  const auto m = mutualMatches(a, b, 40, 0.8);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0], std::make_pair(0, 1));
  EXPECT_EQ(m[1], std::make_pair(1, 0));
  EXPECT_EQ(mutualMatches(a, b, 10, 0.8).size(), 1u);  // only the exact one within 10 bits
  EXPECT_TRUE(mutualMatches(a, cv::Mat(0, 32, CV_8U), 40, 0.8).empty());
}

}  // namespace
}  // namespace rmap::loop
