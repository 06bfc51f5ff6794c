#pragma once
/// @file test_worlds.h
/// Small hand-made worlds and poses shared by the simulator tests.

#include <Eigen/Geometry>

#include "sim/voxel_world.h"

namespace rmap::sim::test {

/// A closed room [−5, 5]² × [0, height_m] inside a 0.3 m shell of one reflectivity.
inline VoxelWorld closedRoom(double height_m, float reflectivity, double voxel_m = 0.05) {
  VoxelWorld w = VoxelWorld::covering(box(-5.3, -5.3, -0.3, 5.3, 5.3, height_m + 0.3), voxel_m);
  w.fillBox(box(-5.3, -5.3, -0.3, 5.3, 5.3, height_m + 0.3), reflectivity);
  w.clearBox(box(-5, -5, 0, 5, 5, height_m));
  return w;
}

/// A pose at (x, y, z) turned by yaw about +z.
inline Eigen::Isometry3d at(double x, double y, double z, double yaw_rad = 0.0) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(x, y, z);
  pose.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return pose;
}

}  // namespace rmap::sim::test
