#include "cli/replay_source.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "datasets/camera_image_file.h"
#include "datasets/carmen_log.h"
#include "datasets/kitti_velodyne.h"
#include "datasets/octomap_graph.h"
#include "datasets/pcd_cloud.h"
#include "datasets/ply_cloud.h"
#include "datasets/pose_file.h"
#include "datasets/uos_3dtk.h"
#include "datasets/xyz_text.h"

namespace rmap::cli {
namespace {

namespace fs = std::filesystem;
using rmap::v1::PointCloud;
using rmap::v1::SensorDescription;

/// The frame files of FILE arguments: files as given, folders expanded to their frame files sorted by name.
std::vector<std::string> frameFiles(ReplayFormat format, const std::vector<std::string>& paths) {
  std::vector<std::string> files;
  for (const std::string& path : paths) {
    if (!fs::is_directory(path)) {
      if (!fs::exists(path)) throw std::runtime_error(path + ": no such file");
      files.push_back(path);
      continue;
    }
    if (format == ReplayFormat::kImages) {
      const std::vector<std::string> images = datasets::listImageFolder(path);
      files.insert(files.end(), images.begin(), images.end());
      continue;
    }
    std::vector<std::string> in_dir;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(path, ec)) {
      if (entry.is_regular_file() && isFrameFile(format, entry.path().string())) in_dir.push_back(entry.path().string());
    }
    if (ec) throw std::runtime_error(path + ": cannot list: " + ec.message());
    if (in_dir.empty()) throw std::runtime_error(path + ": holds no " + std::string(toString(format)) + " frame file");
    std::sort(in_dir.begin(), in_dir.end());
    files.insert(files.end(), in_dir.begin(), in_dir.end());
  }
  return files;
}

void setPose(rmap::v1::Pose3& out, const Eigen::Isometry3d& pose) {
  const Eigen::Quaterniond q(pose.linear());
  out.mutable_position_m()->set_x(pose.translation().x());
  out.mutable_position_m()->set_y(pose.translation().y());
  out.mutable_position_m()->set_z(pose.translation().z());
  out.mutable_orientation()->set_w(q.w());
  out.mutable_orientation()->set_x(q.x());
  out.mutable_orientation()->set_y(q.y());
  out.mutable_orientation()->set_z(q.z());
}

SensorDescription sensor(const std::string& name, SensorDescription::Kind kind, const std::string& model) {
  SensorDescription s;
  s.set_name(name);
  s.set_kind(kind);
  s.set_model(model);
  s.mutable_mount()->mutable_orientation()->set_w(1.0);
  return s;
}

int64_t periodStamp(size_t i, double period_s) { return std::llround(static_cast<double>(i) * period_s * 1e9); }

/// A cloud message; non-finite points (and their intensities) are dropped.
ReplayFrame cloudFrame(const std::vector<Eigen::Vector3f>& points, const std::vector<float>& intensities,
                       const Eigen::Isometry3d& sensor_pose, PointCloud::Frame frame, int64_t stamp_ns) {
  ReplayFrame out;
  out.stamp_ns = stamp_ns;
  PointCloud& cloud = *out.message.mutable_cloud();
  cloud.set_sensor("lidar");
  cloud.set_stamp_ns(stamp_ns);
  cloud.set_frame(frame);
  setPose(*cloud.mutable_sensor_pose(), sensor_pose);
  cloud.mutable_xyz_m()->Reserve(static_cast<int>(3 * points.size()));
  const bool with_intensity = !intensities.empty();
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite() || (with_intensity && !std::isfinite(intensities[i]))) {
      ++out.dropped_points;
      continue;
    }
    for (int a = 0; a < 3; ++a) cloud.add_xyz_m(points[i][a]);
    if (with_intensity) cloud.add_intensities(intensities[i]);
  }
  out.points = points.size() - out.dropped_points;
  return out;
}

/// Scans already in the world frame (scan.dat, 3DTK): MAP-frame clouds from their origins; empty ones skipped.
ReplaySource worldScans(ReplayFormat format, std::vector<datasets::PointScan> scans, double period_s) {
  ReplaySource source;
  source.format = format;
  source.sensors.push_back(sensor("lidar", SensorDescription::LIDAR_3D, toString(format)));
  const size_t all = scans.size();
  std::erase_if(scans, [](const datasets::PointScan& s) { return s.points_m.empty(); });
  if (scans.empty()) throw std::runtime_error("no scan with points");
  if (scans.size() != all) source.notes.push_back(std::to_string(all - scans.size()) + " empty scans skipped");
  auto shared = std::make_shared<std::vector<datasets::PointScan>>(std::move(scans));
  source.frames = shared->size();
  source.frame = [shared, period_s](size_t i) {
    const datasets::PointScan& s = (*shared)[i];
    Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
    origin.translation() = s.sensor_origin_m.cast<double>();
    return cloudFrame(s.points_m, {}, origin, PointCloud::MAP, periodStamp(i, period_s));
  };
  return source;
}

/// The intensity scalar of a PLY vertex, if any ("intensity", CloudCompare's "scalar_intensity", "reflectance").
const std::vector<float>* plyIntensity(const datasets::PlyCloud& cloud) {
  for (const auto& [name, values] : cloud.scalars) {
    std::string n = name;
    std::transform(n.begin(), n.end(), n.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (n == "intensity" || n == "scalar_intensity" || n == "reflectance") return &values;
  }
  return nullptr;
}

ReplaySource carmenSource(const std::vector<std::string>& paths, const ReplaySourceOptions& options) {
  if (paths.size() != 1) {
    throw std::runtime_error("a CARMEN log is one robot's run: replay one log per call (got " +
                             std::to_string(paths.size()) + " files)");
  }
  const std::string& path = paths[0];
  auto log = std::make_shared<datasets::CarmenLog>(datasets::readCarmenLog(path));
  if (log->scans.empty()) throw std::runtime_error(path + ": no FLASER or ROBOTLASER1 scan");
  // The Hello declares one laser: every scan must have the first one's model and mount.
  const slam2d::LaserScan& first = log->scans.front().scan;
  for (const datasets::CarmenScan& s : log->scans) {
    const slam2d::Pose2 d = slam2d::between(first.sensor_mount, s.scan.sensor_mount);
    if (s.scan.model != first.model || d.translation().norm() > 1e-6 || std::abs(d.theta_rad) > 1e-6) {
      throw std::runtime_error(path + ":" + std::to_string(s.line) + ": the laser (" + s.scan.model +
                               ") or its mount differs from the first scan's; a replay declares one laser");
    }
  }
  ReplaySource source;
  source.format = ReplayFormat::kCarmen;
  SensorDescription laser = sensor("laser", SensorDescription::LASER_2D, first.model);
  Eigen::Isometry3d mount = Eigen::Isometry3d::Identity();
  mount.linear() = Eigen::AngleAxisd(first.sensor_mount.theta_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  mount.translation() = Eigen::Vector3d(first.sensor_mount.x_m, first.sensor_mount.y_m, options.laser_height_m);
  setPose(*laser.mutable_mount(), mount);
  source.sensors.push_back(laser);

  // Odometry as rmap-bench slam2d's default: a corrected log (ODOM restarting at every scan) gives
  // the wheel increments of its ODOM lines, a raw log its logged robot poses, a log without ODOM none.
  auto odometry = std::make_shared<std::vector<std::optional<slam2d::Pose2>>>(log->scans.size());
  if (datasets::odometryRestartsAtScans(*log)) {
    *odometry = datasets::odometryFromOdomIncrements(*log);
    source.notes.push_back("odometry: the increments of the ODOM lines (a corrected log)");
  } else if (!log->odometry.empty()) {
    for (size_t k = 0; k < log->scans.size(); ++k) (*odometry)[k] = log->scans[k].robot_pose;
    source.notes.push_back("odometry: the logged robot poses (a raw log)");
  } else {
    source.notes.push_back("odometry: none (the log has no ODOM line)");
  }
  size_t errors = 0;
  for (const datasets::CarmenScan& s : log->scans) {
    errors += std::count_if(s.scan.ranges_m.begin(), s.scan.ranges_m.end(), [](float r) { return std::isnan(r); });
  }
  if (errors > 0) source.notes.push_back(std::to_string(errors) + " error readings (range <= 0) sent as no return");
  source.frames = log->scans.size();
  source.frame = [log, odometry](size_t i) {
    const slam2d::LaserScan& s = log->scans[i].scan;
    ReplayFrame out;
    out.stamp_ns = s.stamp_ns;
    rmap::v1::LaserScan2D& m = *out.message.mutable_scan();
    m.set_sensor("laser");
    m.set_stamp_ns(s.stamp_ns);
    m.set_range_min_m(s.range_min_m);
    m.set_range_max_m(s.range_max_m);
    // The compact form only when the server's angle_min + i·increment gives every angle exactly.
    const size_t n = s.angles_rad.size();
    const float increment = n > 1 ? s.angles_rad[1] - s.angles_rad[0] : 0.0f;
    bool regular = n > 1 && increment != 0.0f;
    for (size_t k = 0; k < n && regular; ++k) regular = s.angles_rad[0] + static_cast<float>(k) * increment == s.angles_rad[k];
    if (regular) {
      m.set_angle_min_rad(s.angles_rad[0]);
      m.set_angle_increment_rad(increment);
    } else {
      m.mutable_angles_rad()->Add(s.angles_rad.begin(), s.angles_rad.end());
    }
    m.mutable_ranges_m()->Reserve(static_cast<int>(n));
    for (const float r : s.ranges_m) {
      // The protocol has no error reading; the SLAM and the 3D map skip NaN and +inf alike.
      m.add_ranges_m(std::isnan(r) ? std::numeric_limits<float>::infinity() : r);
      out.points += std::isfinite(r);
    }
    m.mutable_intensities()->Add(s.intensities.begin(), s.intensities.end());
    if (const std::optional<slam2d::Pose2>& o = (*odometry)[i]) {
      m.mutable_odometry()->set_x_m(o->x_m);
      m.mutable_odometry()->set_y_m(o->y_m);
      m.mutable_odometry()->set_theta_rad(o->theta_rad);
    }
    return out;
  };
  return source;
}

/// Formats of one file per frame, posed by the poses file when given.
ReplaySource perFrameSource(ReplayFormat format, const std::vector<std::string>& paths,
                            const ReplaySourceOptions& options) {
  auto files = std::make_shared<std::vector<std::string>>(frameFiles(format, paths));
  auto poses = std::make_shared<std::vector<datasets::StampedPose3>>();
  if (!options.poses_path.empty()) {
    *poses = datasets::readPoseFile(options.poses_path);
    if (poses->size() != files->size()) {
      throw std::runtime_error(options.poses_path + ": " + std::to_string(poses->size()) + " poses for " +
                               std::to_string(files->size()) + " frames (one pose per frame, in frame order)");
    }
  }
  ReplaySource source;
  source.format = format;
  source.frames = files->size();
  source.reads_per_frame = true;
  const bool images = format == ReplayFormat::kImages;
  source.sensors.push_back(images ? sensor("camera", SensorDescription::CAMERA, "images")
                                  : sensor("lidar", SensorDescription::LIDAR_3D, toString(format)));
  if (poses->empty()) {
    source.notes.push_back(images ? "no --poses: images carry no camera pose"
                                  : "no --poses: every cloud is taken in the map frame from the origin");
  }
  const double period_s = options.period_s;
  source.frame = [format, files, poses, period_s](size_t i) {
    const std::string& file = (*files)[i];
    const bool posed = !poses->empty();
    const Eigen::Isometry3d pose = posed ? (*poses)[i].pose : Eigen::Isometry3d::Identity();
    const int64_t stamp = posed && (*poses)[i].stamp_ns ? *(*poses)[i].stamp_ns : periodStamp(i, period_s);
    if (format == ReplayFormat::kImages) {
      const datasets::CameraImageFile image = datasets::readCameraImageFile(file);
      ReplayFrame out;
      out.stamp_ns = stamp;
      rmap::v1::CameraImage& m = *out.message.mutable_image();
      m.set_sensor("camera");
      m.set_stamp_ns(stamp);
      m.set_encoding(image.encoding == datasets::ImageEncoding::kJpeg ? rmap::v1::CameraImage::JPEG
                                                                      : rmap::v1::CameraImage::PNG);
      m.set_width(static_cast<uint32_t>(image.width_px));
      m.set_height(static_cast<uint32_t>(image.height_px));
      m.set_data(image.bytes);
      if (posed) setPose(*m.mutable_camera_pose(), pose);
      return out;
    }
    std::vector<Eigen::Vector3f> points;
    std::vector<float> intensities;
    if (format == ReplayFormat::kVelodyneBin) {
      datasets::VelodyneFrame f = datasets::readVelodyneBin(file);
      points = std::move(f.points_m);
      intensities = std::move(f.intensities);
    } else if (format == ReplayFormat::kPly) {
      datasets::PlyCloud c = datasets::readPlyCloud(file);
      if (const std::vector<float>* i = plyIntensity(c)) intensities = *i;
      points = std::move(c.points_m);
    } else {
      datasets::PcdCloud c = datasets::readPcdCloud(file);
      points = std::move(c.points_m);
      intensities = std::move(c.intensities);
    }
    ReplayFrame out = cloudFrame(points, intensities, pose, posed ? PointCloud::SENSOR : PointCloud::MAP, stamp);
    if (out.points == 0) throw std::runtime_error(file + ": no finite point");
    return out;
  };
  return source;
}

}  // namespace

ReplaySource openReplaySource(ReplayFormat format, const std::vector<std::string>& paths,
                              const ReplaySourceOptions& options) {
  if (paths.empty()) throw std::runtime_error("no file to replay");
  if (!(options.period_s > 0.0) || !std::isfinite(options.period_s)) {
    throw std::runtime_error("the frame period must be finite and > 0");
  }
  switch (format) {
    case ReplayFormat::kCarmen: return carmenSource(paths, options);
    case ReplayFormat::kOctomapGraph: {
      ReplaySource source;
      source.format = format;
      source.sensors.push_back(sensor("lidar", SensorDescription::LIDAR_3D, "graph"));
      auto scans = std::make_shared<std::vector<datasets::GraphScan>>();
      size_t empty = 0;
      for (const std::string& path : paths) {
        for (datasets::GraphScan& s : datasets::readOctomapGraph(path)) {
          if (s.points_m.empty()) {
            ++empty;
          } else {
            scans->push_back(std::move(s));
          }
        }
      }
      if (scans->empty()) throw std::runtime_error(paths[0] + ": no scan with points");
      if (empty > 0) source.notes.push_back(std::to_string(empty) + " empty scans skipped");
      source.frames = scans->size();
      const double period_s = options.period_s;
      source.frame = [scans, period_s](size_t i) {
        const datasets::GraphScan& s = (*scans)[i];
        return cloudFrame(s.points_m, {}, s.sensor_pose, PointCloud::SENSOR, periodStamp(i, period_s));
      };
      return source;
    }
    case ReplayFormat::kXyzText: {
      std::vector<datasets::PointScan> scans;
      for (const std::string& path : paths) {
        std::vector<datasets::PointScan> more = datasets::readXyzText(path);
        scans.insert(scans.end(), std::make_move_iterator(more.begin()), std::make_move_iterator(more.end()));
      }
      try {
        return worldScans(format, std::move(scans), options.period_s);
      } catch (const std::runtime_error& e) {
        throw std::runtime_error(paths[0] + ": " + e.what());
      }
    }
    case ReplayFormat::kUos3dtk: {
      if (paths.size() != 1 || !fs::is_directory(paths[0])) {
        throw std::runtime_error("3DTK scans come as one folder (holding scan000.3d and its .pose or .frames)");
      }
      datasets::UosReadStats stats;
      std::vector<datasets::PointScan> scans = datasets::readUos3dtk(paths[0], &stats);
      ReplaySource source;
      try {
        source = worldScans(format, std::move(scans), options.period_s);
      } catch (const std::runtime_error& e) {
        throw std::runtime_error(paths[0] + ": " + e.what());
      }
      const size_t dropped = stats.dropped_near + stats.dropped_far + stats.dropped_non_finite;
      if (dropped > 0) {
        source.notes.push_back(std::to_string(dropped) + " of " + std::to_string(stats.points_read) +
                               " points dropped by the 3DTK range limits or as non-finite");
      }
      return source;
    }
    case ReplayFormat::kVelodyneBin:
    case ReplayFormat::kPly:
    case ReplayFormat::kPcd:
    case ReplayFormat::kImages: return perFrameSource(format, paths, options);
  }
  throw std::runtime_error("unknown format");
}

}  // namespace rmap::cli
