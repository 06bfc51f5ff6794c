#pragma once
/// @file slam2d_layer.h
/// A map's 2D SLAM state: one slam2d::Slam2d fed in log order with the
/// map's laser scans (and odometry messages as priors), and read access to
/// its grid for the raster tiles and the map_server export. The worker
/// writes; HTTP handlers read under a shared lock.

#include <atomic>
#include <map>
#include <optional>
#include <shared_mutex>
#include <string>

#include "app/config.h"
#include "app/layer_tiles.h"
#include "app/metrics.h"
#include "app/robot_sensors.h"
#include "loop/reflectivity_patch.h"
#include "rmap/v1/robot_stream.pb.h"
#include "slam2d/intensity_calibration.h"
#include "slam2d/slam2d.h"

namespace rmap::app {

/// Intensity calibration per scanner model.
using Calibrations = std::map<std::string, slam2d::IntensityCalibration>;

/// Reads and parses the configured calibration files.
/// @throws std::invalid_argument naming the model, the file and what is wrong
Calibrations loadCalibrations(const Slam2dConfig& config);

/// One scan put through the SLAM.
struct Slam2dResult {
  slam2d::Pose2 base_pose;    ///< robot base in the map frame
  slam2d::Pose2 sensor_pose;  ///< laser in the map frame
  slam2d::LaserScan scan;     ///< the scan as the SLAM took it (sensor frame)
  std::vector<slam2d::LoopClosure2d> closures;  ///< geometric loop closures accepted with this scan
  /// Accepted geometric closures this scan's optimisation dropped (after `closures`: one may be in both).
  std::vector<slam2d::LoopClosure2d> withdrawn_closures;
  /// The pose graph moved poses: trajectory() and the grid are corrected.
  bool graph_changed = false;
};

class Slam2dLayer {
 public:
  /// @param options       the SLAM's options (rmapd: Slam2dConfig::options, validated with the config)
  /// @param calibrations  per scanner model; other models are self-calibrated by the SLAM
  Slam2dLayer(const slam2d::Slam2dOptions& options, const Calibrations& calibrations, Metrics& metrics);

  /// Processes a scan of `robot_id` taken with `laser` (identity mount and no
  /// model when the robot declared none). Odometry: the scan's own, else the
  /// robot's latest Odometry message.
  /// @return nullopt when the SLAM refused the scan (logged; the state is unchanged)
  std::optional<Slam2dResult> addScan(const std::string& robot_id, const v1::LaserScan2D& scan,
                                      const std::optional<Laser2dSetup>& laser);
  /// Accepts the closures still waiting for a later optimisation (ingest
  /// paused: nothing tests them for now) and returns them.
  std::vector<slam2d::LoopClosure2d> confirmLoopClosures();
  /// Keeps the robot's latest odometry as the prior of its next scans.
  void addOdometry(const std::string& robot_id, const v1::Odometry& odometry);

  /// Whether any scan went into the map (else the map has no 2D layer).
  bool hasLayer() const { return scans_.load() > 0; }
  /// Changes whenever the grid changed (the SLAM's map version).
  uint64_t version() const { return version_.load(); }
  uint64_t scans() const { return scans_.load(); }

  /// Every scan's corrected robot pose of a trajectory, in scan order (see slam2d::Slam2d::trajectory).
  std::vector<slam2d::StampedPose2> trajectory(const std::string& robot_id) const;

  /// The reflectivity patch around a pose (place recognition of 2D-laser robots), under the shared lock.
  cv::Mat reflectivityPatch(const slam2d::Pose2& center, const loop::PatchOptions& options) const;

  /// Runs fn(const Grid2dSource&) under the shared lock and returns its result.
  template <typename Fn>
  auto read(Fn&& fn) const {
    std::shared_lock lock(mutex_);
    return fn(static_cast<const Grid2dSource&>(source_));
  }

 private:
  /// The SLAM's finest grid as the rasters read it.
  class Source : public Grid2dSource {
   public:
    explicit Source(const slam2d::Slam2d& slam) : slam_(slam) {}
    double resolutionM() const override;
    Eigen::AlignedBox2i knownCells() const override;
    float probability(const Eigen::Vector2i& cell) const override;
    float reflectivity(const Eigen::Vector2i& cell) const override;

   private:
    const slam2d::Slam2d& slam_;
  };

  Metrics& metrics_;
  mutable std::shared_mutex mutex_;
  slam2d::Slam2d slam_;
  Source source_{slam_};
  std::map<std::string, slam2d::Pose2> odometry_;  ///< worker thread only
  std::atomic<uint64_t> scans_{0};
  std::atomic<uint64_t> version_{0};
};

}  // namespace rmap::app
