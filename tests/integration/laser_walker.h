#pragma once
/// @file laser_walker.h
/// The 2D-laser robot the end-to-end tests drive through a simulated
/// building: a SICK-like laser 1 m above the floor on a planned tour of
/// 0.26 m steps (tour seed 5, noise seed 11), so tests share one tour.

#include "client/laser2d_robot.h"
#include "sim/trajectory.h"
#include "sim/voxel_world.h"

namespace rmap::testing {

inline constexpr double kWalkerLaserHeight_m = 1.0;

/// @param world  outlives the robot
inline client::Laser2dRobot buildingWalker(const sim::VoxelWorld& world, int tour_poses) {
  sim::TrajectoryOptions path;
  path.sensor_height_m = kWalkerLaserHeight_m;
  path.num_poses = tour_poses;
  path.step_m = 0.26;
  client::Laser2dRobotOptions laser;
  laser.mount_height_m = kWalkerLaserHeight_m;
  return client::Laser2dRobot(world, sim::planTrajectory(world, path, 5), laser, 11);
}

}  // namespace rmap::testing
