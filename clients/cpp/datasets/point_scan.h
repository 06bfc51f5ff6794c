#pragma once
/// @file point_scan.h
/// One 3D scan as the dataset readers return it.

#include <Eigen/Core>
#include <vector>

namespace rmap::datasets {

/// Points of one scan in the world frame: metres, right-handed (x forward,
/// y left, z up for the datasets that define a forward direction).
struct PointScan {
  Eigen::Vector3f sensor_origin_m = Eigen::Vector3f::Zero();  ///< sensor position when the scan was taken
  std::vector<Eigen::Vector3f> points_m;                      ///< end points of the returns
};

}  // namespace rmap::datasets
