#pragma once
/// @file scene_clouds.h
/// Lidar clouds along a planned trajectory through a simulated building, as
/// robot messages, for tests that need to know exactly what was streamed.

#include <random>
#include <vector>

#include "client/sim_feed.h"
#include "rmap/v1/robot_stream.pb.h"
#include "sim/lidar.h"
#include "sim/trajectory.h"

namespace rmap::testing {

/// `count` PointCloud messages (map frame, with intensities) along a
/// trajectory of the scene; deterministic in `seed`.
inline std::vector<v1::RobotMessage> sceneClouds(const client::SimScene& scene, int count, uint64_t seed) {
  sim::TrajectoryOptions trajectory;
  trajectory.num_poses = count;
  trajectory.sensor_height_m = 1.3;
  const std::vector<Eigen::Isometry3d> poses = sim::planTrajectory(scene.world, trajectory, seed);
  sim::LidarModel lidar;
  lidar.rings = 16;
  lidar.columns = 360;
  lidar.max_range_m = 20.0;
  std::mt19937_64 rng(seed);
  std::vector<v1::RobotMessage> out;
  for (const Eigen::Isometry3d& pose : poses) {
    const sim::LidarScan scan = sim::simulateLidar(scene.world, pose, lidar, rng);
    v1::RobotMessage message;
    v1::PointCloud* cloud = message.mutable_cloud();
    cloud->set_sensor("lidar");
    cloud->set_stamp_ns(static_cast<int64_t>(out.size()) * 100'000'000);
    cloud->set_frame(v1::PointCloud::MAP);
    const Eigen::Quaterniond q(pose.linear());
    cloud->mutable_sensor_pose()->mutable_position_m()->set_x(pose.translation().x());
    cloud->mutable_sensor_pose()->mutable_position_m()->set_y(pose.translation().y());
    cloud->mutable_sensor_pose()->mutable_position_m()->set_z(pose.translation().z());
    cloud->mutable_sensor_pose()->mutable_orientation()->set_w(q.w());
    cloud->mutable_sensor_pose()->mutable_orientation()->set_x(q.x());
    cloud->mutable_sensor_pose()->mutable_orientation()->set_y(q.y());
    cloud->mutable_sensor_pose()->mutable_orientation()->set_z(q.z());
    for (size_t i = 0; i < scan.points_m.size(); ++i) {
      if (!std::isfinite(scan.true_ranges_m[i])) continue;  // no return: nothing to send
      for (int a = 0; a < 3; ++a) cloud->add_xyz_m(scan.points_m[i][a]);
      cloud->add_intensities(scan.intensities[i]);
    }
    out.push_back(std::move(message));
  }
  return out;
}

}  // namespace rmap::testing
