#pragma once
/// @file ingest.h
/// Checking robot messages and turning them into engine input. Pure
/// functions: used alike by live sessions and by recovery from the log.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "app/config.h"
#include "map3d/cell_key.h"
#include "rmap/v1/robot_stream.pb.h"

namespace rmap::app {

/// Base cell edges a map may be created with (m): by a Hello or an import.
inline constexpr double kMinResolution_m = 0.005;
inline constexpr double kMaxResolution_m = 10.0;

/// Characters allowed in robot ids and map names: [A-Za-z0-9._-], 1..64.
bool validName(const std::string& name);

/// Checks a Hello; returns what is wrong, empty when valid.
std::string checkHello(const v1::Hello& hello);

/// Checks a data message (everything but Hello) against the protocol, the
/// limits and the map it goes to: 1 <= seq < 2^63, a body, finite values,
/// consistent sizes, known encodings, a cloud origin inside `grid`'s cells.
/// @return what is wrong, empty when the message is valid
std::string checkDataMessage(const v1::RobotMessage& message, const LimitsConfig& limits, const map3d::Grid& grid);

/// A received robot frame: the checked message, or the Error refusing it
/// (docs/API.md §5: code, text, the seq of a message that parsed, fatal).
struct RobotFrame {
  std::shared_ptr<v1::RobotMessage> message;  ///< null when refused
  std::string code;                           ///< invalid_message, hello_required or invalid_hello
  std::string problem;
  uint64_t seq = 0;
  bool fatal = false;
};

/// What a robot stream does with every frame before acting on it: parses it
/// as a RobotMessage, then checks it as the stream's Hello while `grid` is
/// null (no map yet), else as a data message for the map of `grid`.
RobotFrame decodeRobotFrame(std::string_view data, bool binary, const map3d::Grid* grid, const LimitsConfig& limits);

/// A pose message as a rigid transform; an all-zero quaternion is identity.
Eigen::Isometry3d toIsometry(const v1::Pose3& pose);

/// A cloud ready for CuboidMap::insertScan.
struct CloudInMap {
  Eigen::Isometry3d sensor_pose = Eigen::Isometry3d::Identity();  ///< map frame
  std::vector<Eigen::Vector3f> points_m;                           ///< map frame
};

/// The rays' origin as the map takes it (m, map frame): the sensor position in float.
Eigen::Vector3f sensorOrigin(const v1::PointCloud& cloud);

/// Puts the cloud's points in the map frame (a checked message is assumed).
CloudInMap cloudInMap(const v1::PointCloud& cloud);

}  // namespace rmap::app
