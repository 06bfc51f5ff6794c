#include "loop/reflectivity_patch.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rmap::loop {

void PatchOptions::validate() const {
  if (size_px < 32 || size_px > 4096) throw std::invalid_argument("PatchOptions: size_px must be in [32, 4096]");
  if (!(pixel_m > 0.0) || !std::isfinite(pixel_m)) throw std::invalid_argument("PatchOptions: pixel_m must be > 0");
  if (!(reflectivity_max > 0.0) || !std::isfinite(reflectivity_max)) {
    throw std::invalid_argument("PatchOptions: reflectivity_max must be > 0");
  }
  if (!(occupied_probability > 0.0 && occupied_probability < 1.0)) {
    throw std::invalid_argument("PatchOptions: occupied_probability must be in (0, 1)");
  }
}

cv::Mat reflectivityPatch(const slam2d::GridMap2d& map, const slam2d::Pose2& center, const PatchOptions& options) {
  options.validate();
  if (!center.isFinite()) throw std::invalid_argument("reflectivityPatch: pose is not finite");
  const int n = options.size_px;
  cv::Mat patch(n, n, CV_8UC1, cv::Scalar(0));
  const double half = 0.5 * n;
  for (int r = 0; r < n; ++r) {
    uint8_t* row = patch.ptr<uint8_t>(r);
    for (int c = 0; c < n; ++c) {
      const Eigen::Vector2d robot((half - r - 0.5) * options.pixel_m, (half - c - 0.5) * options.pixel_m);
      const Eigen::Vector2i cell = map.cellOf(center * robot);
      const float p = map.probability(cell);
      if (!(p > options.occupied_probability)) continue;  // NaN (unknown) too
      const slam2d::ReflectivityCell rho = map.reflectivity(cell);
      const double shade = rho.count == 0 ? 0.0 : std::clamp(rho.mean / options.reflectivity_max, 0.0, 1.0);
      row[c] = static_cast<uint8_t>(std::lround(64.0 + 191.0 * shade));
    }
  }
  return patch;
}

slam2d::Pose2 patchMotion(const Eigen::Isometry2d& reference_from_query_px, const PatchOptions& options) {
  options.validate();
  // Pixel (x, y) shows robot-frame point ((N/2 − ½ − y)·pixel_m, (N/2 − ½ − x)·pixel_m): a
  // reflection and a scale, the same in both patches, so the robots moved by the pixels' motion
  // seen through it (the reflection turns the pixels' rotation the other way).
  const double centre_m = (0.5 * options.size_px - 0.5) * options.pixel_m;
  Eigen::Affine2d robot_from_px = Eigen::Affine2d::Identity();
  robot_from_px.linear() << 0.0, -options.pixel_m, -options.pixel_m, 0.0;
  robot_from_px.translation() = Eigen::Vector2d(centre_m, centre_m);
  const Eigen::Affine2d motion = robot_from_px * reference_from_query_px * robot_from_px.inverse();
  return {motion.translation().x(), motion.translation().y(), std::atan2(motion.linear()(1, 0), motion.linear()(0, 0))};
}

}  // namespace rmap::loop
