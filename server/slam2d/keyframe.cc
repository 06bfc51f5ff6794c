#include "slam2d/keyframe.h"

#include <cmath>

namespace rmap::slam2d {

std::vector<Ray> keyframeRays(const Keyframe& keyframe, const Pose2& pose) {
  std::vector<Ray> rays;
  rays.reserve(keyframe.ends_robot.size());
  for (const Eigen::Vector2f& e : keyframe.ends_robot) rays.push_back({pose * e.cast<double>(), true});
  return rays;
}

std::vector<Ray> insertKeyframe(GridMap2d& map, const Keyframe& keyframe, const Pose2& pose,
                                const IntensityCalibration* calibration, const OccupancyUpdate& update) {
  std::vector<Ray> rays = keyframeRays(keyframe, pose);
  if (rays.empty()) return rays;
  map.insert((pose * keyframe.sensor_mount).translation(), rays, update, keyframe.range_max_m);
  if (calibration && !keyframe.intensity.empty()) {
    for (size_t i = 0; i < rays.size(); ++i) {
      const double rho = calibration->reflectivity(keyframe.intensity[i], keyframe.range_m[i], keyframe.cos_incidence[i]);
      if (std::isfinite(rho)) map.addReflectivity(rays[i].end_m, static_cast<float>(rho));
    }
  }
  return rays;
}

}  // namespace rmap::slam2d
