#include "loop/panorama.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace rmap::loop {
namespace {

/// A cylinder wall of radius r around the sensor, `rings` rings evenly from
/// −15° to +15°, intensity 10 on the half x > 0 and 90 on x < 0.
struct Cloud {
  std::vector<Eigen::Vector3f> points;
  std::vector<float> intensities;
};

Cloud cylinder(int rings, int columns, double radius_m = 5.0) {
  Cloud c;
  for (int i = 0; i < rings; ++i) {
    const double e = (-15.0 + 30.0 * i / (rings - 1)) * std::numbers::pi / 180.0;
    for (int j = 0; j < columns; ++j) {
      const double a = 2.0 * std::numbers::pi * (j + 0.5) / columns - std::numbers::pi;
      const double d = radius_m / std::cos(e);
      const Eigen::Vector3f p(d * std::cos(e) * std::cos(a), d * std::cos(e) * std::sin(a), d * std::sin(e));
      c.points.push_back(p);
      c.intensities.push_back(p.x() > 0 ? 10.0f : 90.0f);
    }
  }
  return c;
}

TEST(Panorama, EquirectangularPutsForwardInTheMiddleAndNormalisesIntensity) {
  const Cloud c = cylinder(16, 2048);
  PanoramaOptions o;
  o.width_px = 256;
  o.height_px = 64;
  o.fov_up_rad = 20.0 * std::numbers::pi / 180.0;
  o.fov_down_rad = -20.0 * std::numbers::pi / 180.0;
  const cv::Mat img = projectPanorama(c.points, c.intensities, o);
  ASSERT_EQ(img.rows, 64);
  ASSERT_EQ(img.cols, 256);
  ASSERT_EQ(img.type(), CV_8UC1);
  // Forward (x > 0, low intensity) is the middle columns; behind is the edges.
  EXPECT_EQ(img.at<uint8_t>(32, 128), 1);
  EXPECT_EQ(img.at<uint8_t>(32, 2), 255);
  EXPECT_EQ(img.at<uint8_t>(32, 253), 255);
  // 16 rings over 64 rows leave empty rows between them; hole filling closes them.
  // (rings at rows 8, 11.7, ..., 56).
  EXPECT_EQ(cv::countNonZero(img.rowRange(8, 57)), 49 * 256);
  // Above +15° there are no points and filling reaches 4 rows at most.
  EXPECT_EQ(img.at<uint8_t>(0, 128), 0);
}

TEST(Panorama, LeftOfForwardIsLeftInTheImage) {
  std::vector<Eigen::Vector3f> points{{5, 0.2f, 0}, {5, -0.2f, 0}};
  std::vector<float> intensity{100.0f, 0.0f};
  PanoramaOptions o;
  o.width_px = 64;
  o.height_px = 32;
  o.fill_iterations = 0;
  o.low_percentile = 0.0;
  o.high_percentile = 1.0;
  const cv::Mat img = projectPanorama(points, intensity, o);
  EXPECT_EQ(img.at<uint8_t>(16, 31), 255);  // y > 0: just left of the middle column
  EXPECT_EQ(img.at<uint8_t>(16, 32), 1);
  EXPECT_EQ(cv::countNonZero(img), 2);
}

TEST(Panorama, ClosestPointWinsAPixel) {
  std::vector<Eigen::Vector3f> points{{10, 0, 0}, {3, 0, 0}, {6, 0, 0}, {4, 3, 0}};
  std::vector<float> intensity{0.0f, 50.0f, 100.0f, 100.0f};
  PanoramaOptions o;
  o.width_px = 64;
  o.height_px = 32;
  o.fill_iterations = 0;
  o.low_percentile = 0.0;
  o.high_percentile = 1.0;
  cv::Mat index;
  const cv::Mat img = projectPanorama(points, intensity, o, index);
  EXPECT_EQ(img.at<uint8_t>(16, 32), 1);  // the 3 m point (50, the lowest kept) hides the others
  ASSERT_EQ(index.type(), CV_32SC1);
  EXPECT_EQ(index.at<int32_t>(16, 32), 1);
  EXPECT_EQ(index.at<int32_t>(16, 25), 3);  // (4, 3): 36.9° left
  EXPECT_EQ(index.at<int32_t>(0, 0), -1);
}

TEST(Panorama, PanoramaPointsPutEachPixelsPointInAPointImage) {
  const std::vector<Eigen::Vector3f> points{{1, 2, 3}, {4, 5, 6}};
  cv::Mat index(2, 3, CV_32SC1, cv::Scalar(-1));
  index.at<int32_t>(0, 2) = 1;
  index.at<int32_t>(1, 0) = 0;
  const cv::Mat image = panoramaPoints(index, points);
  ASSERT_EQ(image.type(), CV_32FC3);
  ASSERT_EQ(image.size(), index.size());
  EXPECT_EQ(image.at<cv::Vec3f>(0, 2), cv::Vec3f(4, 5, 6));
  EXPECT_EQ(image.at<cv::Vec3f>(1, 0), cv::Vec3f(1, 2, 3));
  EXPECT_TRUE(std::isnan(image.at<cv::Vec3f>(0, 0)[0]));
  index.at<int32_t>(1, 1) = 2;  // beyond the points
  EXPECT_THROW(panoramaPoints(index, points), std::invalid_argument);
  EXPECT_THROW(panoramaPoints(cv::Mat(2, 3, CV_32FC1), points), std::invalid_argument);
}

TEST(Panorama, RingByColumnGivesEachRingAnEqualBand) {
  // Uneven ring spacing: a dense group near the horizon and two far rings.
  std::vector<Eigen::Vector3f> points;
  std::vector<float> intensity;
  const double elevations_deg[] = {-20.0, -2.0, -1.0, 0.0, 1.0, 10.0};
  for (int i = 0; i < 6; ++i) {
    const double e = elevations_deg[i] * std::numbers::pi / 180.0;
    for (int j = 0; j < 720; ++j) {
      const double a = 2.0 * std::numbers::pi * j / 720.0;
      points.emplace_back(8 * std::cos(e) * std::cos(a), 8 * std::cos(e) * std::sin(a), 8 * std::sin(e));
      intensity.push_back(static_cast<float>(i));
    }
  }
  PanoramaOptions o;
  o.projection = PanoramaProjection::kRingByColumn;
  o.width_px = 360;
  o.height_px = 60;
  o.low_percentile = 0.0;
  o.high_percentile = 1.0;
  const cv::Mat img = projectPanorama(points, intensity, o);  // rings found from the gaps
  for (int band = 0; band < 6; ++band) {
    const int ring = 5 - band;  // top ring first
    const uint8_t expected = static_cast<uint8_t>(std::lround(1.0 + 254.0 * ring / 5.0));
    for (int v = band * 10; v < band * 10 + 10; ++v) EXPECT_EQ(img.at<uint8_t>(v, 100), expected) << v;
  }
  o.ring_count = 3;  // the three widest gaps split the cloud into 3 rings only... 2 gaps: below −2° and above 1°
  const cv::Mat three = projectPanorama(points, intensity, o);
  EXPECT_EQ(three.at<uint8_t>(5, 0), 255);   // top band: the +10° ring
  EXPECT_EQ(three.at<uint8_t>(55, 0), 1);    // bottom band: the −20° ring
}

TEST(Panorama, EstimatesTheRingsOfAUniformLidar) {
  const Cloud c = cylinder(32, 400);
  const std::vector<float> rings = estimateRingElevations(c.points, 0);
  ASSERT_EQ(rings.size(), 32u);
  EXPECT_NEAR(rings.front(), -15.0 * std::numbers::pi / 180.0, 1e-4);
  EXPECT_NEAR(rings.back(), 15.0 * std::numbers::pi / 180.0, 1e-4);
  EXPECT_EQ(estimateRingElevations(c.points, 32), rings);
}

TEST(Panorama, DropsNoReturnsAndNonFiniteValues) {
  std::vector<Eigen::Vector3f> points{{0, 0, 0}, {5, 0, 0}, {NAN, 0, 0}, {-5, 0, 0}};
  std::vector<float> intensity{200.0f, 10.0f, 10.0f, NAN};
  PanoramaOptions o;
  o.width_px = 64;
  o.height_px = 32;
  o.fill_iterations = 0;
  const cv::Mat img = projectPanorama(points, intensity, o);
  EXPECT_EQ(cv::countNonZero(img), 1);
  EXPECT_EQ(img.at<uint8_t>(16, 32), 128);  // a single intensity has no spread: mid grey
}

TEST(Panorama, BadInputThrows) {
  const Cloud c = cylinder(4, 16);
  PanoramaOptions o;
  std::vector<float> short_intensities(c.points.size() - 1, 1.0f);
  EXPECT_THROW(projectPanorama(c.points, short_intensities, o), std::invalid_argument);
  o.width_px = 8;
  EXPECT_THROW(projectPanorama(c.points, c.intensities, o), std::invalid_argument);
  o = {};
  o.fov_down_rad = o.fov_up_rad;
  EXPECT_THROW(projectPanorama(c.points, c.intensities, o), std::invalid_argument);
  o = {};
  o.low_percentile = 0.9;
  o.high_percentile = 0.5;
  EXPECT_THROW(projectPanorama(c.points, c.intensities, o), std::invalid_argument);
  EXPECT_THROW(estimateRingElevations(c.points, 1000), std::invalid_argument);
  EXPECT_THROW(estimateRingElevations({}, 0), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::loop
