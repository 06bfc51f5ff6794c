#pragma once
/// @file camera.h
/// A grey pinhole camera rendered by ray casting into a VoxelWorld, with a
/// light level, so the same place can be seen by day, under other lights, or
/// in the dark (where only sensor noise is left).
///
/// Camera frame as the lidar's: x forward (optical axis), y left, z up. Pixel
/// (u, v), u to the right and v down, looks along (f, cx − u − ½, cy − v − ½)
/// with f = (width/2) / tan(hfov/2), cx = width/2, cy = height/2 (square pixels).
///
/// Radiometry (Lambertian, no shadows): a surface of reflectivity ρ and face
/// normal n gives the signal s = 255 · ρ · light_level · (ambient + (1 − ambient) · max(0, −n·l))
/// (l the unit direction the light travels; rays that hit nothing within
/// max_range_m give 0), and the grey value is
///   g = clamp(k · (s + σ·N(0, 1)), 0, 255)
/// with σ the read noise (amplified with the gain, as in a real sensor) and
/// k = lighting.gain, times, with auto exposure, the factor that brings the
/// mean signal to target_mean_grey, limited to [1/max_auto_gain, max_auto_gain]:
/// a camera that adapts to dim light until its gain runs out, so in the dark
/// it shows amplified noise. Voxel faces are axis-aligned, so walls are flat
/// shaded; texture comes from the reflectivity pattern of the world.

#include <Eigen/Geometry>
#include <cstdint>
#include <random>
#include <vector>

#include "sim/voxel_world.h"

namespace rmap::sim {

struct CameraModel {
  int width_px = 320;          ///< [8, 8192]
  int height_px = 240;         ///< [8, 8192]
  double hfov_rad = 1.2217;    ///< horizontal field of view (70°), (0, 3]
  double max_range_m = 50.0;   ///< metres, > 0
  bool auto_exposure = true;
  double target_mean_grey = 100.0;  ///< auto exposure aims at this mean, (0, 255)
  double max_auto_gain = 16.0;      ///< ≥ 1

  /// @throws std::invalid_argument naming the first bad parameter
  void validate() const;
};

struct Lighting {
  double light_level = 1.0;    ///< scale of all light, ≥ 0 (1: day; ≈ 0: dark)
  Eigen::Vector3d light_direction{-0.3, -0.4, -0.866};  ///< direction the light travels (normalised), world frame
  double ambient = 0.4;        ///< share of light reaching every face, [0, 1]
  double gain = 1.0;           ///< exposure, > 0
  double noise_sigma = 2.0;    ///< grey levels of additive Gaussian sensor noise, ≥ 0

  /// @throws std::invalid_argument naming the first bad parameter
  void validate() const;
};

/// 8-bit grey image, row-major.
struct GreyImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> pixels;  ///< height · width
  uint8_t at(int u, int v) const { return pixels[static_cast<size_t>(v) * width + u]; }
};

/// Renders one image. O(pixels · ray length).
/// @param camera_pose_world  camera frame → world frame
/// @param rng  noise source; one normal draw per pixel in row-major order (none when noise_sigma is 0)
/// @throws std::invalid_argument for a bad model or lighting
GreyImage renderCamera(const VoxelWorld& world, const Eigen::Isometry3d& camera_pose_world, const CameraModel& model,
                       const Lighting& lighting, std::mt19937_64& rng);

}  // namespace rmap::sim
