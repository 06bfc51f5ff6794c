#include "app/ingest.h"

#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>

namespace rmap::app {

namespace {

bool finite(const v1::Vector3& v) { return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z()); }

std::string checkPose(const v1::Pose3& pose, const char* what) {
  const v1::Quaternion& q = pose.orientation();
  const double norm2 = q.w() * q.w() + q.x() * q.x() + q.y() * q.y() + q.z() * q.z();
  if (!finite(pose.position_m()) || !std::isfinite(norm2)) return std::string(what) + " is not finite";
  // All zero reads as identity (an unset field); anything else must be close to unit length.
  if (norm2 != 0.0 && std::abs(norm2 - 1.0) > 1e-3) {
    return std::string(what) + " orientation is not a unit quaternion";
  }
  return {};
}

template <typename Floats>
bool allFinite(const Floats& values) {
  for (const float v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

std::string checkCloud(const v1::PointCloud& cloud, const LimitsConfig& limits, const map3d::Grid& grid) {
  const int n = cloud.xyz_m_size();
  if (n == 0) return "cloud has no points";
  if (n % 3 != 0) return "cloud xyz_m holds " + std::to_string(n) + " values, not a multiple of 3";
  if (static_cast<size_t>(n / 3) > limits.max_points_per_cloud) {
    return "cloud has " + std::to_string(n / 3) + " points, more than the limit of " +
           std::to_string(limits.max_points_per_cloud);
  }
  if (!cloud.intensities().empty() && cloud.intensities_size() != n / 3) {
    return "cloud has " + std::to_string(cloud.intensities_size()) + " intensities for " + std::to_string(n / 3) +
           " points";
  }
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(cloud.xyz_m(i))) return "cloud point " + std::to_string(i / 3) + " is not finite";
  }
  if (!allFinite(cloud.intensities())) return "cloud intensities are not all finite";
  if (std::string e = checkPose(cloud.sensor_pose(), "cloud sensor_pose"); !e.empty()) return e;
  // The map cannot take rays from outside its cells: refused here, before the message is made durable.
  map3d::CellKey origin_cell;
  if (!grid.cellChecked(sensorOrigin(cloud), origin_cell)) {
    std::ostringstream text;
    text << "cloud sensor_pose position is outside the map's addressable range (±"
         << map3d::kCellLimit * grid.resolution() << " m per axis)";
    return text.str();
  }
  return {};
}

std::string checkScan(const v1::LaserScan2D& scan) {
  const int n = scan.ranges_m_size();
  if (n == 0) return "scan has no ranges";
  if (!(scan.range_min_m() >= 0.0f) || !(scan.range_max_m() > scan.range_min_m()) ||
      !std::isfinite(scan.range_max_m())) {
    return "scan needs finite 0 <= range_min_m < range_max_m";
  }
  for (int i = 0; i < n; ++i) {
    const float r = scan.ranges_m(i);
    if (std::isnan(r) || r < 0.0f) return "scan range " + std::to_string(i) + " is NaN or negative";
  }
  if (!scan.intensities().empty() && scan.intensities_size() != n) return "scan needs one intensity per range";
  if (!allFinite(scan.intensities())) return "scan intensities are not all finite";
  if (!scan.angles_rad().empty()) {
    if (scan.angles_rad_size() != n) return "scan needs one angle per range";
    if (!allFinite(scan.angles_rad())) return "scan angles are not all finite";
  } else if (!std::isfinite(scan.angle_min_rad()) || !std::isfinite(scan.angle_increment_rad()) ||
             scan.angle_increment_rad() == 0.0f) {
    return "scan needs finite angle_min_rad and a finite non-zero angle_increment_rad";
  }
  if (scan.has_odometry()) {
    const v1::Pose2& p = scan.odometry();
    if (!std::isfinite(p.x_m()) || !std::isfinite(p.y_m()) || !std::isfinite(p.theta_rad())) {
      return "scan odometry is not finite";
    }
  }
  return {};
}

std::string checkImage(const v1::CameraImage& image) {
  const std::string& data = image.data();
  if (data.empty()) return "image has no data";
  switch (image.encoding()) {
    case v1::CameraImage::JPEG:
      if (data.size() < 3 || std::memcmp(data.data(), "\xFF\xD8\xFF", 3) != 0) return "image data is not a JPEG";
      break;
    case v1::CameraImage::PNG:
      if (data.size() < 8 || std::memcmp(data.data(), "\x89PNG\r\n\x1A\n", 8) != 0) return "image data is not a PNG";
      break;
    case v1::CameraImage::MONO8:
    case v1::CameraImage::RGB8: {
      const uint64_t channels = image.encoding() == v1::CameraImage::RGB8 ? 3 : 1;
      if (image.width() == 0 || image.height() == 0) return "raw image needs width > 0 and height > 0";
      // width·height fits in 64 bits (both are 32-bit), times channels may not: a wrapped
      // product could equal the size of a small payload.
      const uint64_t pixels = uint64_t{image.width()} * image.height();
      if (pixels > UINT64_MAX / channels) {
        return "raw image of " + std::to_string(image.width()) + "x" + std::to_string(image.height()) +
               " pixels is too large";
      }
      const uint64_t expected = pixels * channels;
      if (data.size() != expected) {
        return "raw image needs width*height*channels = " + std::to_string(expected) + " bytes, got " +
               std::to_string(data.size());
      }
      break;
    }
    default:
      return "image encoding must be JPEG, PNG, MONO8 or RGB8";
  }
  if (image.has_camera_pose()) return checkPose(image.camera_pose(), "image camera_pose");
  return {};
}

}  // namespace

bool validName(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  for (const char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                    c == '_' || c == '-';
    if (!ok) return false;
  }
  return true;
}

std::string checkHello(const v1::Hello& hello) {
  if (!validName(hello.robot_id())) return "robot_id must be 1..64 characters of [A-Za-z0-9._-]";
  if (!validName(hello.map())) return "map must be 1..64 characters of [A-Za-z0-9._-]";
  if (!std::isfinite(hello.resolution_m()) || hello.resolution_m() < 0.0 ||
      (hello.resolution_m() > 0.0 && (hello.resolution_m() < kMinResolution_m || hello.resolution_m() > kMaxResolution_m))) {
    return "resolution_m must be 0 (server default) or within [0.005, 10] m";
  }
  for (const v1::SensorDescription& s : hello.sensors()) {
    if (const std::string e = checkPose(s.mount(), "sensor mount"); !e.empty()) return e;
  }
  return {};
}

std::string checkDataMessage(const v1::RobotMessage& message, const LimitsConfig& limits, const map3d::Grid& grid) {
  if (message.seq() == 0) return "seq must be >= 1";
  // The log keeps seq in a signed 64-bit column; a larger one would fail its whole commit batch.
  if (message.seq() > static_cast<uint64_t>(INT64_MAX)) return "seq must be below 2^63";
  switch (message.body_case()) {
    case v1::RobotMessage::kCloud: return checkCloud(message.cloud(), limits, grid);
    case v1::RobotMessage::kScan: return checkScan(message.scan());
    case v1::RobotMessage::kImage: return checkImage(message.image());
    case v1::RobotMessage::kOdometry: return checkPose(message.odometry().pose(), "odometry pose");
    case v1::RobotMessage::kHello: return "hello was already received on this stream";
    case v1::RobotMessage::BODY_NOT_SET: break;
  }
  return "message has no body";
}

RobotFrame decodeRobotFrame(std::string_view data, bool binary, const map3d::Grid* grid, const LimitsConfig& limits) {
  const auto refuse = [](const char* code, std::string problem, uint64_t seq, bool fatal) {
    return RobotFrame{nullptr, code, std::move(problem), seq, fatal};
  };
  if (!binary) return refuse("invalid_message", "robot frames must be binary protobuf RobotMessage", 0, false);
  auto message = std::make_shared<v1::RobotMessage>();
  if (data.size() > static_cast<size_t>(INT_MAX) ||
      !message->ParseFromArray(data.data(), static_cast<int>(data.size()))) {
    return refuse("invalid_message", "the frame is not a valid rmap.v1.RobotMessage", 0, false);
  }
  const uint64_t seq = message->seq();
  if (!grid) {
    if (message->body_case() != v1::RobotMessage::kHello) {
      return refuse("hello_required", "the first message of a robot stream must be Hello", seq, true);
    }
    if (std::string problem = checkHello(message->hello()); !problem.empty()) {
      return refuse("invalid_hello", std::move(problem), 0, true);
    }
  } else if (std::string problem = checkDataMessage(*message, limits, *grid); !problem.empty()) {
    return refuse("invalid_message", std::move(problem), seq, false);
  }
  return RobotFrame{std::move(message), {}, {}, seq, false};
}

Eigen::Isometry3d toIsometry(const v1::Pose3& pose) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  const v1::Quaternion& q = pose.orientation();
  if (q.w() != 0.0 || q.x() != 0.0 || q.y() != 0.0 || q.z() != 0.0) {
    t.linear() = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).normalized().toRotationMatrix();
  }
  t.translation() = Eigen::Vector3d(pose.position_m().x(), pose.position_m().y(), pose.position_m().z());
  return t;
}

Eigen::Vector3f sensorOrigin(const v1::PointCloud& cloud) {
  const v1::Vector3& p = cloud.sensor_pose().position_m();
  return Eigen::Vector3d(p.x(), p.y(), p.z()).cast<float>();
}

CloudInMap cloudInMap(const v1::PointCloud& cloud) {
  CloudInMap out;
  out.sensor_pose = toIsometry(cloud.sensor_pose());
  const size_t n = static_cast<size_t>(cloud.xyz_m_size()) / 3;
  out.points_m.resize(n);
  // Eigen::Vector3f is three packed floats, the wire layout of xyz_m.
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
  if (n > 0) std::memcpy(out.points_m.front().data(), cloud.xyz_m().data(), n * sizeof(Eigen::Vector3f));
  if (cloud.frame() == v1::PointCloud::SENSOR) {
    const Eigen::Isometry3f pose = out.sensor_pose.cast<float>();
    for (Eigen::Vector3f& p : out.points_m) p = pose * p;
  }
  return out;
}

}  // namespace rmap::app
