#include "loop/point_image.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace rmap::loop {

bool isPointImage(const cv::Mat& points_m, cv::Size size) {
  return points_m.type() == CV_32FC3 && points_m.size() == size;
}

std::optional<Eigen::Vector3f> pointNear(const cv::Mat& points_m, cv::Point2f pixel, int radius_px) {
  if (!std::isfinite(pixel.x) || !std::isfinite(pixel.y)) return std::nullopt;
  const int u0 = static_cast<int>(std::floor(pixel.x)), v0 = static_cast<int>(std::floor(pixel.y));
  for (int r = 0; r <= radius_px; ++r) {
    // The ring of pixels r away, nearer rows first (0, −1, +1, −2, …).
    for (int k = 0; k <= 2 * r; ++k) {
      const int dv = k % 2 == 0 ? k / 2 : -(k + 1) / 2;
      const int v = v0 + dv;
      if (v < 0 || v >= points_m.rows) continue;
      for (int du = -r; du <= r; ++du) {
        if (std::max(std::abs(du), std::abs(dv)) != r) continue;
        const int u = u0 + du;
        if (u < 0 || u >= points_m.cols) continue;
        const cv::Vec3f& p = points_m.at<cv::Vec3f>(v, u);
        if (std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2])) return Eigen::Vector3f(p[0], p[1], p[2]);
      }
    }
  }
  return std::nullopt;
}

}  // namespace rmap::loop
