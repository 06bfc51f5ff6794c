#pragma once
// Synthetic grey scenes for the loop tests: random rectangles, circles and
// lines (corners and edges for the detectors), the same for a given seed.

#include <opencv2/imgproc.hpp>
#include <random>

namespace rmap::loop::test {

inline cv::Mat texturedScene(uint32_t seed, int width = 320, int height = 240) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> x(0, width - 1), y(0, height - 1), grey(0, 255), size(4, 40);
  cv::Mat img(height, width, CV_8UC1, cv::Scalar(grey(rng)));
  for (int i = 0; i < 150; ++i) {
    const cv::Point p(x(rng), y(rng));
    switch (i % 3) {
      case 0: cv::rectangle(img, p, p + cv::Point(size(rng), size(rng)), cv::Scalar(grey(rng)), cv::FILLED); break;
      case 1: cv::circle(img, p, size(rng) / 2, cv::Scalar(grey(rng)), cv::FILLED); break;
      default: cv::line(img, p, cv::Point(x(rng), y(rng)), cv::Scalar(grey(rng)), 2); break;
    }
  }
  cv::GaussianBlur(img, img, cv::Size(3, 3), 0.8);
  return img;
}

/// `img` moved by (dx, dy) pixels, the uncovered border filled by replication.
inline cv::Mat shifted(const cv::Mat& img, double dx, double dy) {
  cv::Mat out;
  const cv::Matx23d m(1, 0, dx, 0, 1, dy);
  cv::warpAffine(img, out, m, img.size(), cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return out;
}

}  // namespace rmap::loop::test
