#include "sim/camera.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rmap::sim {

void CameraModel::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("CameraModel: " + what); };
  if (width_px < 8 || width_px > 8192 || height_px < 8 || height_px > 8192) fail("width_px, height_px must be in [8, 8192]");
  if (!(hfov_rad > 0.0 && hfov_rad <= 3.0)) fail("hfov_rad must be in (0, 3]");
  if (!(max_range_m > 0.0) || !std::isfinite(max_range_m)) fail("max_range_m must be finite and > 0");
  if (!(target_mean_grey > 0.0 && target_mean_grey < 255.0)) fail("target_mean_grey must be in (0, 255)");
  if (!(max_auto_gain >= 1.0) || !std::isfinite(max_auto_gain)) fail("max_auto_gain must be finite and ≥ 1");
}

void Lighting::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("Lighting: " + what); };
  if (!(light_level >= 0.0) || !std::isfinite(light_level)) fail("light_level must be finite and ≥ 0");
  if (!light_direction.allFinite() || light_direction.norm() < 1e-9) fail("light_direction must be a finite non-zero vector");
  if (!(ambient >= 0.0 && ambient <= 1.0)) fail("ambient must be in [0, 1]");
  if (!(gain > 0.0) || !std::isfinite(gain)) fail("gain must be finite and > 0");
  if (!(noise_sigma >= 0.0) || !std::isfinite(noise_sigma)) fail("noise_sigma must be finite and ≥ 0");
}

GreyImage renderCamera(const VoxelWorld& world, const Eigen::Isometry3d& camera_pose_world, const CameraModel& model,
                       const Lighting& lighting, std::mt19937_64& rng) {
  model.validate();
  lighting.validate();
  const double f = 0.5 * model.width_px / std::tan(0.5 * model.hfov_rad);
  const double cx = 0.5 * model.width_px, cy = 0.5 * model.height_px;
  const Eigen::Vector3d origin = camera_pose_world.translation();
  const Eigen::Matrix3d rotation = camera_pose_world.linear();
  const Eigen::Vector3d light = lighting.light_direction.normalized();
  const double scale = 255.0 * lighting.light_level;
  std::normal_distribution<double> noise(0.0, 1.0);

  std::vector<double> signal(static_cast<size_t>(model.width_px) * model.height_px, 0.0);
  for (int v = 0; v < model.height_px; ++v) {
    for (int u = 0; u < model.width_px; ++u) {
      const Eigen::Vector3d dir = (rotation * Eigen::Vector3d(f, cx - u - 0.5, cy - v - 0.5)).normalized();
      if (const std::optional<RayHit> hit = world.castRay(origin, dir, model.max_range_m)) {
        const double lit = lighting.ambient + (1.0 - lighting.ambient) * std::max(0.0, -hit->normal.dot(light));
        signal[static_cast<size_t>(v) * model.width_px + u] = scale * hit->reflectivity * lit;
      }
    }
  }
  double gain = lighting.gain;
  if (model.auto_exposure) {
    double mean = 0.0;
    for (double s : signal) mean += s;
    mean /= static_cast<double>(signal.size());
    const double wanted = mean > 0.0 ? model.target_mean_grey / (gain * mean) : model.max_auto_gain;
    gain *= std::clamp(wanted, 1.0 / model.max_auto_gain, model.max_auto_gain);
  }
  GreyImage image{model.width_px, model.height_px, std::vector<uint8_t>(signal.size())};
  for (size_t k = 0; k < signal.size(); ++k) {
    const double read = lighting.noise_sigma > 0.0 ? lighting.noise_sigma * noise(rng) : 0.0;
    image.pixels[k] = static_cast<uint8_t>(std::clamp(std::lround(gain * (signal[k] + read)), 0L, 255L));
  }
  return image;
}

}  // namespace rmap::sim
