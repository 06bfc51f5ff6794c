#pragma once
/// @file lidar_pair.h
/// Reading the real lidar pair (../shared/data/lidar-intensity): two PLY scans
/// and the rigid transform between them, as the calibration and the
/// place-recognition sanity checks both use it.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "datasets/ply_cloud.h"

namespace rmap::bench {

/// A 4×4 row-major homogeneous transform from a text file of 16 numbers.
/// @throws std::runtime_error when the file cannot be read or holds fewer numbers
Eigen::Matrix4d readTransform(const std::string& path);

/// The per-vertex scalar named like "intensity" or "reflectivity".
/// @param path  the cloud's file, for the error message
/// @throws std::runtime_error when the cloud has no such property
const std::vector<float>& intensityOf(const datasets::PlyCloud& cloud, const std::string& path);

}  // namespace rmap::bench
