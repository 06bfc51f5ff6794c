#include "app/slam2d_layer.h"

#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "app/ingest.h"

namespace rmap::app {

namespace {

slam2d::LaserScan toLaserScan(const v1::LaserScan2D& in, const std::optional<Laser2dSetup>& laser) {
  slam2d::LaserScan scan;
  scan.stamp_ns = in.stamp_ns();
  if (laser) {
    scan.model = laser->model;
    scan.sensor_mount = {laser->x_m, laser->y_m, laser->yaw_rad};
  }
  scan.range_min_m = in.range_min_m();
  scan.range_max_m = in.range_max_m();
  const int n = in.ranges_m_size();
  scan.angles_rad.resize(static_cast<size_t>(n));
  scan.ranges_m.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    scan.angles_rad[i] = in.angles_rad().empty()
                             ? in.angle_min_rad() + static_cast<float>(i) * in.angle_increment_rad()
                             : in.angles_rad(i);
    // Beyond range_max_m is a no return by the protocol (§5.2), whatever the SLAM's own limits.
    const float r = in.ranges_m(i);
    scan.ranges_m[i] = r > in.range_max_m() ? std::numeric_limits<float>::infinity() : r;
  }
  scan.intensities.assign(in.intensities().begin(), in.intensities().end());
  return scan;
}

slam2d::Pose2 planar(const Eigen::Isometry3d& pose) {
  const Eigen::Vector3d x_axis = pose.linear().col(0);
  return {pose.translation().x(), pose.translation().y(), std::atan2(x_axis.y(), x_axis.x())};
}

}  // namespace

Calibrations loadCalibrations(const Slam2dConfig& config) {
  Calibrations out;
  for (const auto& [model, file] : config.calibration_files) {
    const std::string what = "slam2d.calibrations: model '" + model + "', file " + file.string();
    std::ifstream in(file, std::ios::binary);
    if (!in) throw std::invalid_argument(what + ": cannot be read");
    std::ostringstream text;
    text << in.rdbuf();
    try {
      out.emplace(model, slam2d::IntensityCalibration::fromText(text.str()));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(what + ": " + e.what());
    }
  }
  return out;
}

Slam2dLayer::Slam2dLayer(const slam2d::Slam2dOptions& options, const Calibrations& calibrations, Metrics& metrics)
    : metrics_(metrics), slam_(options) {
  for (const auto& [model, calibration] : calibrations) slam_.setCalibration(model, calibration);
}

std::optional<Slam2dResult> Slam2dLayer::addScan(const std::string& robot_id, const v1::LaserScan2D& in,
                                                 const std::optional<Laser2dSetup>& laser) {
  Slam2dResult result;
  result.scan = toLaserScan(in, laser);
  std::optional<slam2d::Pose2> odometry;
  if (in.has_odometry()) {
    odometry = slam2d::Pose2{in.odometry().x_m(), in.odometry().y_m(), in.odometry().theta_rad()};
  } else if (const auto it = odometry_.find(robot_id); it != odometry_.end()) {
    odometry = it->second;
  }
  const auto start = std::chrono::steady_clock::now();
  try {
    std::unique_lock lock(mutex_);
    const uint64_t graph_version = slam_.graphVersion();
    result.base_pose = slam_.addScan(robot_id, result.scan, odometry);
    result.closures = slam_.takeLoopClosures();
    result.withdrawn_closures = slam_.takeWithdrawnLoopClosures();
    result.graph_changed = slam_.graphVersion() != graph_version;
    version_.store(slam_.version());
  } catch (const std::invalid_argument& e) {
    metrics_.slam2d_scans_refused.fetch_add(1, std::memory_order_relaxed);
    spdlog::warn("2D SLAM: scan of {} at {} ns not used: {}", robot_id, in.stamp_ns(), e.what());
    return std::nullopt;
  }
  metrics_.slam2d_scan_latency.observe(
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  metrics_.slam2d_scans.fetch_add(1, std::memory_order_relaxed);
  scans_.fetch_add(1);
  result.sensor_pose = result.base_pose * result.scan.sensor_mount;
  return result;
}

std::vector<slam2d::LoopClosure2d> Slam2dLayer::confirmLoopClosures() {
  std::unique_lock lock(mutex_);
  slam_.confirmLoopClosures();
  return slam_.takeLoopClosures();
}

void Slam2dLayer::addOdometry(const std::string& robot_id, const v1::Odometry& odometry) {
  odometry_[robot_id] = planar(toIsometry(odometry.pose()));
}

std::vector<slam2d::StampedPose2> Slam2dLayer::trajectory(const std::string& robot_id) const {
  std::shared_lock lock(mutex_);
  return slam_.trajectory(robot_id);
}

cv::Mat Slam2dLayer::reflectivityPatch(const slam2d::Pose2& center, const loop::PatchOptions& options) const {
  std::shared_lock lock(mutex_);
  return loop::reflectivityPatch(slam_.grid(), center, options);
}

double Slam2dLayer::Source::resolutionM() const { return slam_.grid().resolution_m(); }

Eigen::AlignedBox2i Slam2dLayer::Source::knownCells() const { return slam_.grid().knownCells(); }

float Slam2dLayer::Source::probability(const Eigen::Vector2i& cell) const { return slam_.grid().probability(cell); }

float Slam2dLayer::Source::reflectivity(const Eigen::Vector2i& cell) const {
  const slam2d::ReflectivityCell r = slam_.grid().reflectivity(cell);
  return r.count > 0 ? static_cast<float>(r.mean) : std::numeric_limits<float>::quiet_NaN();
}

}  // namespace rmap::app
