#include "app/robot_sensors.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rmap::app {
namespace {

v1::Hello helloWithLaser(const std::string& model, double x_m, double z_m, double yaw_rad) {
  v1::Hello hello;
  hello.set_robot_id("bot");
  v1::SensorDescription* s = hello.add_sensors();
  s->set_name("front");
  s->set_kind(v1::SensorDescription::LASER_2D);
  s->set_model(model);
  s->mutable_mount()->mutable_position_m()->set_x(x_m);
  s->mutable_mount()->mutable_position_m()->set_z(z_m);
  s->mutable_mount()->mutable_orientation()->set_w(std::cos(yaw_rad / 2));
  s->mutable_mount()->mutable_orientation()->set_z(std::sin(yaw_rad / 2));
  v1::SensorDescription* lidar = hello.add_sensors();
  lidar->set_name("top");
  lidar->set_kind(v1::SensorDescription::LIDAR_3D);
  return hello;
}

TEST(RobotSensors, LasersOfAHelloCarryTheirPlanarMount) {
  const std::vector<Laser2dSetup> lasers = lasersOf(helloWithLaser("lms", 0.2, 0.4, 0.5));
  ASSERT_EQ(lasers.size(), 1u);
  EXPECT_EQ(lasers[0].name, "front");
  EXPECT_EQ(lasers[0].model, "lms");
  EXPECT_DOUBLE_EQ(lasers[0].x_m, 0.2);
  EXPECT_DOUBLE_EQ(lasers[0].z_m, 0.4);
  EXPECT_NEAR(lasers[0].yaw_rad, 0.5, 1e-12);
}

TEST(RobotSensors, EachSessionsMessagesKeepTheirHellosLaser) {
  RobotSensors sensors;
  const auto first = lasersOf(helloWithLaser("lms", 0.2, 0.4, 0.0));
  const auto second = lasersOf(helloWithLaser("utm", 0.1, 0.3, 0.0));
  ASSERT_TRUE(sensors.isNew("bot", 0, first));
  sensors.add("bot", 0, first);
  EXPECT_FALSE(sensors.isNew("bot", 0, first));
  EXPECT_FALSE(sensors.isNew("bot", 40, first));  // same laser after a reconnect: nothing new
  ASSERT_TRUE(sensors.isNew("bot", 40, second));
  sensors.add("bot", 40, second);
  EXPECT_EQ(sensors.laser("bot", 40, "front")->model, "lms");  // numbered in the first session
  EXPECT_EQ(sensors.laser("bot", 41, "front")->model, "utm");
  EXPECT_EQ(sensors.laser("bot", 41, "other")->model, "utm");  // the only laser
  EXPECT_FALSE(sensors.laser("nobody", 1, "front"));
}

TEST(RobotSensors, StoredSetsRestoreTheSameAnswers) {
  RobotSensors live, replayed;
  const auto lasers = lasersOf(helloWithLaser("lms", 0.2, 0.4, 0.25));
  live.add("bot", 7, lasers);
  replayed.addJson(lasersJson("bot", 7, lasers));
  EXPECT_EQ(replayed.laser("bot", 8, "front"), live.laser("bot", 8, "front"));
  EXPECT_FALSE(replayed.laser("bot", 7, "front"));
  EXPECT_THROW(replayed.addJson("{\"robot_id\": 3}"), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::app
