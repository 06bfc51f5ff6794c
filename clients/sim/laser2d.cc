#include "sim/laser2d.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace rmap::sim {

void Laser2dModel::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("Laser2dModel: " + what); };
  if (!(fov_deg > 0.0 && fov_deg <= 360.0)) fail("fov_deg must be in (0, 360]");
  if (beams < 2) fail("beams must be ≥ 2");
  if (!(min_range_m >= 0.0)) fail("min_range_m must be ≥ 0");
  if (!(max_range_m > min_range_m) || !std::isfinite(max_range_m)) fail("max_range_m must be finite and > min_range_m");
  if (!(range_noise_sigma_m >= 0.0) || !std::isfinite(range_noise_sigma_m)) fail("range_noise_sigma_m must be ≥ 0");
  intensity.validate();
}

Laser2dModel Laser2dModel::sickLike() {
  Laser2dModel m;
  m.name = "sick_like";
  m.fov_deg = 270.0;
  m.beams = 541;
  m.max_range_m = 25.0;
  m.min_range_m = 0.05;
  m.range_noise_sigma_m = 0.012;
  m.intensity.gain = 1500.0;
  m.intensity.range_exponent = 1.2;
  m.intensity.incidence_exponent = 0.6;
  m.intensity.near_range_m = 0.5;
  m.intensity.near_exponent = 3.0;
  m.intensity.saturation = 1000.0;
  m.intensity.noise_rel_sigma = 0.02;
  return m;
}

Laser2dModel Laser2dModel::hokuyoLike() {
  Laser2dModel m;
  m.name = "hokuyo_like";
  m.fov_deg = 270.0;
  m.beams = 1081;
  m.max_range_m = 30.0;
  m.min_range_m = 0.1;
  m.range_noise_sigma_m = 0.01;
  m.intensity.gain = 60000.0;
  m.intensity.range_exponent = 2.2;
  m.intensity.incidence_exponent = 1.5;
  m.intensity.near_range_m = 1.5;
  m.intensity.near_exponent = 4.0;
  m.intensity.saturation = 12000.0;
  m.intensity.noise_rel_sigma = 0.05;
  return m;
}

Laser2dScan simulateLaser2d(const VoxelWorld& world, const Eigen::Isometry3d& sensor_pose_world,
                            const Laser2dModel& model, std::mt19937_64& rng) {
  model.validate();
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const double fov = model.fov_deg * std::numbers::pi / 180.0;
  const double increment = fov / (model.beams - 1);
  std::normal_distribution<double> range_noise(0.0, 1.0);
  const Eigen::Vector3d origin = sensor_pose_world.translation();

  Laser2dScan scan;
  scan.model_name = model.name;
  scan.angle_min_rad = static_cast<float>(-0.5 * fov);
  scan.angle_max_rad = static_cast<float>(0.5 * fov);
  scan.angle_increment_rad = static_cast<float>(increment);
  scan.range_min_m = static_cast<float>(model.min_range_m);
  scan.range_max_m = static_cast<float>(model.max_range_m);
  scan.ranges_m.reserve(model.beams);
  for (int i = 0; i < model.beams; ++i) {
    const double angle = -0.5 * fov + i * increment;
    const Eigen::Vector3d dir =
        (sensor_pose_world.linear() * Eigen::Vector3d(std::cos(angle), std::sin(angle), 0.0)).normalized();
    const std::optional<RayHit> hit = world.castRay(origin, dir, model.max_range_m);
    if (!hit) {
      scan.ranges_m.push_back(kInf);
      scan.intensities.push_back(0.0f);
      scan.true_ranges_m.push_back(kInf);
      scan.reflectivities.push_back(0.0f);
      continue;
    }
    scan.true_ranges_m.push_back(static_cast<float>(hit->range_m));
    if (hit->range_m < model.min_range_m) {
      scan.ranges_m.push_back(-kInf);
      scan.intensities.push_back(0.0f);
      scan.reflectivities.push_back(0.0f);
      continue;
    }
    const double measured = std::max(0.0, hit->range_m + model.range_noise_sigma_m * range_noise(rng));
    scan.ranges_m.push_back(static_cast<float>(measured));
    scan.intensities.push_back(static_cast<float>(
        model.intensity.sample(hit->reflectivity, hit->range_m, std::abs(dir.dot(hit->normal)), rng)));
    scan.reflectivities.push_back(hit->reflectivity);
  }
  return scan;
}

}  // namespace rmap::sim
