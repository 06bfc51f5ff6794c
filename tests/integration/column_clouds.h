#pragma once
/// @file column_clouds.h
/// Clouds that each leave a mark of their own, for tests that must tell from
/// the map which messages are in it, and how often. Cloud `index` casts 9
/// rays straight up from (x, y, 0.05 m) to a 3×3 patch of endpoints 2 m
/// higher, 0.2 m apart, in a column 0.8 m from every other index's: no ray
/// of one cloud touches another's cells (at 0.1 m cells). An endpoint cell
/// is then unknown when its cloud is not in the map, occupied with the
/// probability of one hit when it was applied once, and more when twice.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "map3d/occupancy_params.h"
#include "rmap/v1/robot_stream.pb.h"

namespace rmap::testing {

/// Columns per row of the layout; 10,000 clouds span 80 m × 80 m.
inline constexpr uint64_t kColumnsPerRow = 100;
inline constexpr double kColumnSpacing_m = 0.8;

/// The 9 endpoints of cloud `index` (m, map frame), at cell centres.
inline std::vector<Eigen::Vector3d> columnEndpoints(uint64_t index) {
  const double x = static_cast<double>(index % kColumnsPerRow) * kColumnSpacing_m + 0.05;
  const double y = static_cast<double>(index / kColumnsPerRow) * kColumnSpacing_m + 0.05;
  std::vector<Eigen::Vector3d> out;
  for (const double dx : {-0.2, 0.0, 0.2}) {
    for (const double dy : {-0.2, 0.0, 0.2}) out.emplace_back(x + dx, y + dy, 2.05);
  }
  return out;
}

/// Cloud `index` in the map frame, sensor below its endpoints.
inline v1::RobotMessage columnCloud(uint64_t index, int64_t stamp_ns) {
  const std::vector<Eigen::Vector3d> endpoints = columnEndpoints(index);
  v1::RobotMessage message;
  v1::PointCloud* cloud = message.mutable_cloud();
  cloud->set_sensor("lidar");
  cloud->set_stamp_ns(stamp_ns);
  cloud->set_frame(v1::PointCloud::MAP);
  v1::Vector3* origin = cloud->mutable_sensor_pose()->mutable_position_m();
  origin->set_x(endpoints[4].x());
  origin->set_y(endpoints[4].y());
  origin->set_z(0.05);
  cloud->mutable_sensor_pose()->mutable_orientation()->set_w(1.0);
  for (const Eigen::Vector3d& p : endpoints) {
    for (int a = 0; a < 3; ++a) cloud->add_xyz_m(static_cast<float>(p[a]));
  }
  return message;
}

/// Occupancy probability of an endpoint cell hit once (default parameters).
inline double oneHitProbability() { return map3d::probability(map3d::OccupancyParams{}.hit_log_odds); }

}  // namespace rmap::testing
