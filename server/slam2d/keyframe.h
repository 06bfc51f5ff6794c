#pragma once
/// @file keyframe.h
/// A keyframe: a scan that went into the map (one per map update), kept so the
/// map can be re-rendered after the pose graph moved it and so older places
/// can be matched again. The scan is stored in the robot base frame; only its
/// pose changes.

#include <Eigen/Core>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "slam2d/grid_map.h"
#include "slam2d/intensity_calibration.h"
#include "slam2d/pose2.h"

namespace rmap::slam2d {

struct Keyframe {
  size_t trajectory = 0;  ///< index of the trajectory (Slam2d's order of first use)
  int64_t stamp_ns = 0;
  Pose2 pose;             ///< robot base pose in the map frame (corrected by the pose graph)
  Pose2 sensor_mount;     ///< sensor pose in the base frame
  float range_max_m = 0;  ///< rays are cut here when inserted (see OccupancyGrid::insert)
  std::vector<Eigen::Vector2f> ends_robot;  ///< every usable beam's endpoint, base frame (m)
  std::vector<Eigen::Vector2d> match_points;  ///< endpoints thinned for matching, base frame (m)
  /// Per beam of ends_robot, only for scans with intensities (else empty):
  /// what the reflectivity layer needs to fuse ρ = I / g(r, α) again.
  std::string model;
  std::vector<float> range_m, intensity, cos_incidence;
};

/// Map-frame endpoints of a keyframe at `pose`.
std::vector<Ray> keyframeRays(const Keyframe& keyframe, const Pose2& pose);

/// Inserts a keyframe at `pose` into every level of `map`, and with a
/// calibration the reflectivity of its returns.
/// @return the map-frame rays it inserted
std::vector<Ray> insertKeyframe(GridMap2d& map, const Keyframe& keyframe, const Pose2& pose,
                                const IntensityCalibration* calibration, const OccupancyUpdate& update);

}  // namespace rmap::slam2d
