#include "sim/lidar.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rmap::sim {

void LidarModel::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("LidarModel: " + what); };
  if (rings < 1 || columns < 1) fail("rings and columns must be ≥ 1");
  if (!(fov_down_deg >= -90.0 && fov_up_deg <= 90.0 && fov_down_deg <= fov_up_deg)) {
    fail("need −90 ≤ fov_down_deg ≤ fov_up_deg ≤ 90");
  }
  if (!(min_range_m >= 0.0)) fail("min_range_m must be ≥ 0");
  if (!(max_range_m > min_range_m) || !std::isfinite(max_range_m)) fail("max_range_m must be finite and > min_range_m");
  if (!(range_noise_sigma_m >= 0.0) || !std::isfinite(range_noise_sigma_m)) fail("range_noise_sigma_m must be ≥ 0");
  intensity.validate();
}

std::vector<Eigen::Vector3d> lidarBeamDirections(const LidarModel& model) {
  model.validate();
  constexpr double kDeg = std::numbers::pi / 180.0;
  std::vector<Eigen::Vector3d> dirs;
  dirs.reserve(static_cast<size_t>(model.rings) * model.columns);
  for (int ring = 0; ring < model.rings; ++ring) {
    const double elevation =
        model.rings == 1 ? 0.5 * (model.fov_up_deg + model.fov_down_deg) * kDeg
                         : (model.fov_down_deg + ring * (model.fov_up_deg - model.fov_down_deg) / (model.rings - 1)) * kDeg;
    for (int column = 0; column < model.columns; ++column) {
      const double azimuth = 2.0 * std::numbers::pi * column / model.columns;
      dirs.emplace_back(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                        std::sin(elevation));
    }
  }
  return dirs;
}

LidarScan simulateLidar(const VoxelWorld& world, const Eigen::Isometry3d& sensor_pose_world, const LidarModel& model,
                        std::mt19937_64& rng) {
  const std::vector<Eigen::Vector3d> beams = lidarBeamDirections(model);
  std::normal_distribution<double> range_noise(0.0, 1.0);
  const Eigen::Vector3d origin = sensor_pose_world.translation();
  const Eigen::Matrix3d rotation = sensor_pose_world.linear();

  LidarScan scan;
  scan.sensor_origin_m = origin.cast<float>();
  for (size_t beam = 0; beam < beams.size(); ++beam) {
    const Eigen::Vector3d dir = (rotation * beams[beam]).normalized();
    const std::optional<RayHit> hit = world.castRay(origin, dir, model.max_range_m);
    if (hit && hit->range_m >= model.min_range_m) {
      const double measured = std::max(0.0, hit->range_m + model.range_noise_sigma_m * range_noise(rng));
      const double cos_incidence = std::abs(dir.dot(hit->normal));
      scan.points_m.push_back((origin + measured * dir).cast<float>());
      scan.intensities.push_back(
          static_cast<float>(model.intensity.sample(hit->reflectivity, hit->range_m, cos_incidence, rng)));
      scan.true_ranges_m.push_back(static_cast<float>(hit->range_m));
      scan.reflectivities.push_back(hit->reflectivity);
    } else if (model.report_no_return) {
      scan.points_m.push_back((origin + (model.max_range_m + 1.0) * dir).cast<float>());
      scan.intensities.push_back(0.0f);
      scan.true_ranges_m.push_back(std::numeric_limits<float>::infinity());
      scan.reflectivities.push_back(0.0f);
    } else {
      continue;
    }
    scan.beam_ids.push_back(static_cast<uint32_t>(beam));
  }
  return scan;
}

}  // namespace rmap::sim
