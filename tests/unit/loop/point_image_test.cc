#include "loop/point_image.h"

#include <gtest/gtest.h>

#include <limits>

namespace rmap::loop {
namespace {

cv::Mat emptyPoints(int rows, int cols) {
  return cv::Mat(rows, cols, CV_32FC3, cv::Scalar::all(std::numeric_limits<float>::quiet_NaN()));
}

TEST(PointImage, AKeypointTakesTheNearestPixelsPointWithinTheRadius) {
  cv::Mat points = emptyPoints(20, 30);
  points.at<cv::Vec3f>(10, 10) = cv::Vec3f(1, 2, 3);
  points.at<cv::Vec3f>(13, 15) = cv::Vec3f(4, 5, 6);
  points.at<cv::Vec3f>(12, 10) = cv::Vec3f(7, 8, std::numeric_limits<float>::infinity());  // not a point
  EXPECT_TRUE(isPointImage(points, cv::Size(30, 20)));
  EXPECT_FALSE(isPointImage(points, cv::Size(20, 30)));
  EXPECT_FALSE(isPointImage(cv::Mat(20, 30, CV_32FC1), cv::Size(30, 20)));

  const auto own = pointNear(points, cv::Point2f(10.7f, 10.2f), 0);  // pixel (10, 10) itself
  ASSERT_TRUE(own);
  EXPECT_EQ(*own, Eigen::Vector3f(1, 2, 3));
  const auto near = pointNear(points, cv::Point2f(14.5f, 12.5f), 1);  // (14, 12): (15, 13) is 1 away
  ASSERT_TRUE(near);
  EXPECT_EQ(*near, Eigen::Vector3f(4, 5, 6));
  // (10, 12): the non-finite pixel is skipped; (10, 10) is 2 away, (15, 13) 5.
  const auto skipped = pointNear(points, cv::Point2f(10.0f, 12.0f), 3);
  ASSERT_TRUE(skipped);
  EXPECT_EQ(*skipped, Eigen::Vector3f(1, 2, 3));
  EXPECT_FALSE(pointNear(points, cv::Point2f(10.0f, 12.0f), 1));
  EXPECT_FALSE(pointNear(points, cv::Point2f(-5.0f, -5.0f), 2));  // outside, nothing within reach
  EXPECT_FALSE(pointNear(points, cv::Point2f(std::nanf(""), 3.0f), 5));
}

}  // namespace
}  // namespace rmap::loop
