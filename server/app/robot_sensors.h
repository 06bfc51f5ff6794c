#pragma once
/// @file robot_sensors.h
/// The 2D lasers robots declared in their Hellos, kept so that a replay of
/// the log gives every scan the sensor it was taken with.
///
/// A Hello's sensors apply to that robot's messages with seq greater than the
/// Welcome's last_durable_seq: messages the robot numbered in that session.
/// Resent messages of an earlier session keep that session's sensors. The
/// sets are stored as events (kind kRobotSensorsEvent) before the Welcome
/// goes out, so live application and replay pick the same set.

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "rmap/v1/robot_stream.pb.h"

namespace rmap::app {

inline constexpr const char* kRobotSensorsEvent = "robot_sensors";

/// A planar laser as the SLAM takes it.
struct Laser2dSetup {
  std::string name;
  std::string model;
  /// Sensor frame in the robot base frame: x, y (m), yaw (rad) for the SLAM,
  /// z (m) for the planar cloud put into the 3D map.
  double x_m = 0.0, y_m = 0.0, z_m = 0.0, yaw_rad = 0.0;
  bool operator==(const Laser2dSetup&) const = default;
};

/// LASER_2D sensors of a Hello.
std::vector<Laser2dSetup> lasersOf(const v1::Hello& hello);
std::string lasersJson(const std::string& robot_id, uint64_t after_seq, const std::vector<Laser2dSetup>& lasers);

class RobotSensors {
 public:
  /// Whether `lasers` differ from what applies to messages of `robot_id` with seq > after_seq now.
  bool isNew(const std::string& robot_id, uint64_t after_seq, const std::vector<Laser2dSetup>& lasers) const;
  /// Records a Hello's lasers for messages of `robot_id` with seq > after_seq.
  void add(const std::string& robot_id, uint64_t after_seq, std::vector<Laser2dSetup> lasers);
  /// Restores a set stored by lasersJson. @throws std::invalid_argument for bad JSON
  void addJson(const std::string& json);
  /// The laser of a scan: the one named `sensor`, else the robot's only
  /// laser; nullopt when neither exists.
  std::optional<Laser2dSetup> laser(const std::string& robot_id, uint64_t seq, const std::string& sensor) const;

 private:
  struct Entry {
    uint64_t after_seq;
    std::vector<Laser2dSetup> lasers;
  };
  const Entry* entryFor(const std::string& robot_id, uint64_t seq) const;  ///< needs mutex_

  mutable std::mutex mutex_;
  std::map<std::string, std::vector<Entry>> entries_;  ///< per robot, in Hello order
};

}  // namespace rmap::app
