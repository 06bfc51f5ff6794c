#pragma once
/// @file kitti_velodyne.h
/// Reader of KITTI-style velodyne frames (`.bin`): packed little-endian
/// float32 records x y z intensity, metres in the sensor frame, no header.

#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

namespace rmap::datasets {

struct VelodyneFrame {
  std::vector<Eigen::Vector3f> points_m;  ///< sensor frame
  std::vector<float> intensities;         ///< one per point (KITTI: reflectance in 0..1)
};

/// @param source  name used in error messages (usually the path)
/// @throws std::runtime_error "<source>: ..." when the size is not a multiple
///         of 16 bytes, or "<source>: offset <n>: ..." at the first non-finite value
VelodyneFrame parseVelodyneBin(std::string_view bytes, const std::string& source);

/// Reads a file (optionally .gz/.bz2 compressed) with parseVelodyneBin.
VelodyneFrame readVelodyneBin(const std::string& path);

}  // namespace rmap::datasets
