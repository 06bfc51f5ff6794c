#include "client/laser2d_robot.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace rmap::client {
namespace {

/// A 10 m × 6 m box room, walls 2 m high, reflectivity 0.5.
sim::VoxelWorld room() {
  sim::VoxelWorld world =
      sim::VoxelWorld::covering(Eigen::AlignedBox3d(Eigen::Vector3d(-5.5, -3.5, -0.5), Eigen::Vector3d(5.5, 3.5, 2.5)), 0.1);
  world.fillBox(Eigen::AlignedBox3d(Eigen::Vector3d(-5, -3, -0.1), Eigen::Vector3d(5, 3, 0)), 0.3f);
  world.fillBox(Eigen::AlignedBox3d(Eigen::Vector3d(-5, -3, 0), Eigen::Vector3d(-4.9, 3, 2)), 0.5f);
  world.fillBox(Eigen::AlignedBox3d(Eigen::Vector3d(4.9, -3, 0), Eigen::Vector3d(5, 3, 2)), 0.5f);
  world.fillBox(Eigen::AlignedBox3d(Eigen::Vector3d(-5, -3, 0), Eigen::Vector3d(5, -2.9, 2)), 0.5f);
  world.fillBox(Eigen::AlignedBox3d(Eigen::Vector3d(-5, 2.9, 0), Eigen::Vector3d(5, 3, 2)), 0.5f);
  return world;
}

/// Three laser poses 0.3 m apart along +x at 1 m height.
std::vector<Eigen::Isometry3d> line() {
  std::vector<Eigen::Isometry3d> tour;
  for (int i = 0; i < 3; ++i) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(0.3 * i, 0.0, 1.0);
    tour.push_back(pose);
  }
  return tour;
}

Laser2dRobotOptions exact() {
  Laser2dRobotOptions o;
  o.odometry_forward_sigma = 0.0;
  o.odometry_lateral_sigma_per_m = 0.0;
  o.odometry_heading_sigma_rad = 0.0;
  return o;
}

TEST(Laser2dRobot, DrivesTheTourForthAndBackWithTheMountedLaser) {
  const sim::VoxelWorld world = room();
  Laser2dRobot robot(world, line(), exact(), 1);
  const v1::SensorDescription sensor = robot.sensor();
  EXPECT_EQ(sensor.kind(), v1::SensorDescription::LASER_2D);
  EXPECT_EQ(sensor.name(), "laser");
  EXPECT_EQ(sensor.model(), "sick_like");
  EXPECT_DOUBLE_EQ(sensor.mount().position_m().x(), 0.15);
  EXPECT_DOUBLE_EQ(sensor.mount().position_m().z(), 1.0);

  // Laser x: 0, 0.3, 0.6, back to 0.3 facing −x, then 0, 0.3 facing +x again
  // (the ends turn round while stepping off them).
  const double laser_x[] = {0.0, 0.3, 0.6, 0.3, 0.0, 0.3};
  const double yaw[] = {0.0, 0.0, 0.0, std::numbers::pi, 0.0, 0.0};
  for (int k = 0; k < 6; ++k) {
    const Laser2dStep step = robot.next();
    const double base_x = laser_x[k] - 0.15 * std::cos(yaw[k]);
    EXPECT_NEAR(step.base_truth.x(), base_x, 1e-9) << k;
    EXPECT_NEAR(step.base_truth.y(), 0.0, 1e-9) << k;
    EXPECT_NEAR(std::abs(std::remainder(step.base_truth.z() - yaw[k], 2 * std::numbers::pi)), 0.0, 1e-9) << k;
    EXPECT_NEAR(step.laser_pose_world.translation().x(), laser_x[k], 1e-9);
    // Without noise the odometry is the truth (in the map frame from the start).
    EXPECT_NEAR(step.scan.odometry().x_m(), step.base_truth.x(), 1e-9) << k;
    EXPECT_NEAR(step.scan.odometry().y_m(), step.base_truth.y(), 1e-9) << k;
    EXPECT_NEAR(std::abs(std::remainder(step.scan.odometry().theta_rad() - step.base_truth.z(), 2 * std::numbers::pi)),
                0.0, 1e-9);
    EXPECT_EQ(step.scan.sensor(), "laser");
    ASSERT_EQ(step.scan.ranges_m_size(), 541);
    ASSERT_EQ(step.scan.intensities_size(), 541);
    // Beam 270 looks along the laser's x: the wall at x = ±4.9.
    const double wall_m = yaw[k] == 0.0 ? 4.9 - laser_x[k] : laser_x[k] + 4.9;
    EXPECT_NEAR(step.scan.ranges_m(270), wall_m, 0.1) << k;
    EXPECT_GT(step.scan.intensities(270), 0.0f);
  }
  EXPECT_EQ(robot.steps(), 6u);
}

TEST(Laser2dRobot, OdometryDriftsDeterministicallyInTheSeed) {
  const sim::VoxelWorld world = room();
  Laser2dRobot a(world, line(), {}, 7), b(world, line(), {}, 7), c(world, line(), {}, 8);
  double drift_m = 0.0;
  bool differs = false;
  for (int k = 0; k < 8; ++k) {
    const Laser2dStep sa = a.next(), sb = b.next(), sc = c.next();
    EXPECT_EQ(sa.scan.SerializeAsString(), sb.scan.SerializeAsString()) << k;
    differs = differs || sa.scan.odometry().x_m() != sc.scan.odometry().x_m();
    const double error_m = std::hypot(sa.scan.odometry().x_m() - sa.base_truth.x(),
                                      sa.scan.odometry().y_m() - sa.base_truth.y());
    if (k == 0) {
      EXPECT_EQ(error_m, 0.0);  // starts at the true pose
    }
    drift_m = std::max(drift_m, error_m);
  }
  EXPECT_TRUE(differs);
  EXPECT_GT(drift_m, 0.0);
  EXPECT_LT(drift_m, 0.5);
}

TEST(Laser2dRobot, SkipResumesTheTourWithTheSameOdometry) {
  const sim::VoxelWorld world = room();
  Laser2dRobot straight(world, line(), {}, 3), resumed(world, line(), {}, 3);
  std::vector<Laser2dStep> steps;
  for (int k = 0; k < 7; ++k) steps.push_back(straight.next());
  resumed.skip(5);
  EXPECT_EQ(resumed.steps(), 5u);
  for (int k = 5; k < 7; ++k) {
    const Laser2dStep step = resumed.next();
    EXPECT_EQ(step.scan.odometry().SerializeAsString(), steps[k].scan.odometry().SerializeAsString()) << k;
    EXPECT_TRUE(step.base_truth.isApprox(steps[k].base_truth)) << k;
  }
}

TEST(Laser2dRobot, RejectsBadInput) {
  const sim::VoxelWorld world = room();
  EXPECT_THROW(Laser2dRobot(world, {}, {}, 1), std::invalid_argument);
  Laser2dRobotOptions o;
  o.odometry_heading_sigma_rad = -1.0;
  EXPECT_THROW(Laser2dRobot(world, line(), o, 1), std::invalid_argument);
  o = {};
  o.mount_height_m = 0.0;
  EXPECT_THROW(Laser2dRobot(world, line(), o, 1), std::invalid_argument);
  o = {};
  o.laser.beams = 1;
  EXPECT_THROW(Laser2dRobot(world, line(), o, 1), std::invalid_argument);
}

TEST(Laser2dRobot, MarkersReachTheLaserPlaneOnEveryStorey) {
  sim::VoxelWorld world =
      sim::VoxelWorld::covering(Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(3, 3, 5)), 0.1);
  sim::BuildingLayout layout;
  // Strips at 1.6 m on the ground storey and 0.85 m above the second storey's floor (z = 3).
  layout.markers = {Eigen::AlignedBox3d(Eigen::Vector3d(1.0, 2.0, 1.6), Eigen::Vector3d(2.0, 2.1, 1.7)),
                    Eigen::AlignedBox3d(Eigen::Vector3d(1.0, 2.0, 3.85), Eigen::Vector3d(2.0, 2.1, 3.95))};
  for (const auto& m : layout.markers) world.fillBox(m, 0.9f);
  extendMarkersToLaserPlane(world, layout, 3.0, 1.0);
  for (const double z : {0.75, 1.0, 1.25, 1.65, 3.75, 4.0, 4.25}) {
    EXPECT_TRUE(world.occupied(Eigen::Vector3d(1.5, 2.05, z))) << z;
  }
  EXPECT_FALSE(world.occupied(Eigen::Vector3d(1.5, 2.05, 0.5)));
  EXPECT_FALSE(world.occupied(Eigen::Vector3d(1.5, 2.05, 2.0)));
  EXPECT_FALSE(world.occupied(Eigen::Vector3d(2.5, 2.05, 1.0)));
}

}  // namespace
}  // namespace rmap::client
