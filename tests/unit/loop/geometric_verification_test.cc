#include "loop/geometric_verification.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

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

/// ORB features of a textured scene and of the same scene shifted by (6, −3) px.
std::pair<Features, Features> sceneAndShifted() {
  auto extractor = makeExtractor();
  const cv::Mat scene = test::texturedScene(11);
  return {extractor->extract(scene), extractor->extract(test::shifted(scene, 6.0, -3.0))};
}

TEST(GeometricVerification, SameSceneHasManyInliersAndAnotherSceneFew) {
  const auto [a, moved] = sceneAndShifted();
  const Features other = makeExtractor()->extract(test::texturedScene(12));
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
  // The fitted motion is the picture's: shifted by (6, −3) px, then turned 25° about the centre.
  ASSERT_TRUE(same.reference_from_query_px);
  const cv::Mat turn = cv::getRotationMatrix2D(cv::Point2f(scene.cols / 2.0f, scene.rows / 2.0f), 25.0, 1.0);
  for (const cv::Point2d p : {cv::Point2d(20, 30), cv::Point2d(300, 200), cv::Point2d(160, 120)}) {
    const cv::Point2d shifted = p + cv::Point2d(6, -3);
    const Eigen::Vector2d truth(turn.at<double>(0, 0) * shifted.x + turn.at<double>(0, 1) * shifted.y + turn.at<double>(0, 2),
                                turn.at<double>(1, 0) * shifted.x + turn.at<double>(1, 1) * shifted.y + turn.at<double>(1, 2));
    EXPECT_LT((*same.reference_from_query_px * Eigen::Vector2d(p.x, p.y) - truth).norm(), 1.0);
  }
  // A zoom fits a fundamental matrix (it sees one plane) but is no rigid motion.
  const GeometricVerificationOptions fundamental;
  EXPECT_GT(verifyGeometry(points(a), a.descriptors, points(zoomed_view), zoomed_view.descriptors, fundamental).inliers,
            20);
  const Verification zoomed =
      verifyGeometry(points(a), a.descriptors, points(zoomed_view), zoomed_view.descriptors, rigid);
  EXPECT_GE(zoomed.matches, 15);
  EXPECT_EQ(zoomed.inliers, 0);
  EXPECT_FALSE(zoomed.reference_from_query_px);
  GeometricVerificationOptions bad = rigid;
  bad.max_scale_error = 1.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

/// One 3D point per keypoint, in a 10 × 6 × 3 m room.
std::vector<Eigen::Vector3f> roomPoints(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> x(-5, 5), y(-3, 3), z(-1, 2);
  std::vector<Eigen::Vector3f> p;
  for (size_t i = 0; i < n; ++i) p.emplace_back(x(rng), y(rng), z(rng));
  return p;
}

/// The points a sensor at `truth` (reference from query) sees of `query` (one per keypoint of
/// `a`) at the keypoints of `moved`, the picture of `a` shifted by (6, −3) px; 2 cm of noise.
std::vector<Eigen::Vector3f> movedPoints(const Features& a, const Features& moved,
                                         const std::vector<Eigen::Vector3f>& query, const Eigen::Isometry3d& truth) {
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.0f, 0.02f);
  // Each keypoint of the shifted image shows the point of the nearest keypoint of `a` 6, −3 px back.
  std::vector<Eigen::Vector3f> reference;
  for (const cv::KeyPoint& k : moved.keypoints) {
    size_t best = 0;
    for (size_t i = 1; i < a.keypoints.size(); ++i) {
      if (cv::norm(a.keypoints[i].pt + cv::Point2f(6, -3) - k.pt) < cv::norm(a.keypoints[best].pt + cv::Point2f(6, -3) - k.pt)) best = i;
    }
    reference.push_back((truth.cast<float>() * query[best]) + Eigen::Vector3f(noise(rng), noise(rng), noise(rng)));
  }
  return reference;
}

/// The reference sensor 1.2 m from the query's and turned 30°.
Eigen::Isometry3d referenceFromQuery() {
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
  truth.linear() = Eigen::AngleAxisd(0.52, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  truth.translation() = Eigen::Vector3d(1.0, -0.6, 0.2);
  return truth;
}

TEST(GeometricVerification, ARigid3dFitRecoversTheMotionOfLiftedKeypointsAndNotAnotherLayout) {
  const auto [a, moved] = sceneAndShifted();
  const std::vector<Eigen::Vector3f> query = roomPoints(a.keypoints.size(), 1);
  const Eigen::Isometry3d truth = referenceFromQuery();
  const std::vector<Eigen::Vector3f> reference = movedPoints(a, moved, query, truth);
  GeometricVerificationOptions o;
  o.model = GeometricModel::kRigid3d;
  const Verification same = verifyRigid3d(query, a.descriptors, reference, moved.descriptors, o);
  EXPECT_GT(same.inliers, 100);
  EXPECT_LE(same.inliers, same.matches);
  EXPECT_LT((same.reference_from_query.translation() - truth.translation()).norm(), 0.05);
  EXPECT_LT(Eigen::AngleAxisd(same.reference_from_query.linear() * truth.linear().transpose()).angle(), 0.01);
  // The same picture over points of another layout: descriptors match, their points do not move rigidly.
  const Verification other =
      verifyRigid3d(query, a.descriptors, roomPoints(moved.keypoints.size(), 2), moved.descriptors, o);
  EXPECT_EQ(other.matches, same.matches);
  EXPECT_LT(other.inliers, 12);
  // Bad input.
  EXPECT_THROW(verifyRigid3d(query, a.descriptors, reference, moved.descriptors.rowRange(0, 10), o),
               std::invalid_argument);
  GeometricVerificationOptions bad = o;
  bad.ransac_threshold_m = 0.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(GeometricVerification, KeypointsAlongOneLineMeasureNoRigid3dMotion) {
  const auto [a, moved] = sceneAndShifted();
  // Every keypoint on one edge 3 m ahead (within 5 cm): a turn about it moves none of them.
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> along(-5.0f, 5.0f), off(-0.05f, 0.05f);
  std::vector<Eigen::Vector3f> query;
  for (size_t k = 0; k < a.keypoints.size(); ++k) query.emplace_back(3.0f + off(rng), along(rng), off(rng));
  GeometricVerificationOptions o;
  o.model = GeometricModel::kRigid3d;
  const Verification v =
      verifyRigid3d(query, a.descriptors, movedPoints(a, moved, query, referenceFromQuery()), moved.descriptors, o);
  EXPECT_GT(v.matches, 100);
  EXPECT_EQ(v.inliers, 0);
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
