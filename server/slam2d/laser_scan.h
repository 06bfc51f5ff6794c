#pragma once
/// @file laser_scan.h
/// One planar laser scan as the 2D SLAM takes it: the sensor's own frame,
/// one range (and optionally one raw intensity) per beam.

#include <cstdint>
#include <string>
#include <vector>

#include "slam2d/pose2.h"

namespace rmap::slam2d {

struct LaserScan {
  int64_t stamp_ns = 0;
  /// Scanner model; intensity calibration is per model.
  std::string model;
  /// Sensor frame in the robot base frame.
  Pose2 sensor_mount;
  /// Beams closer than range_min_m or farther than range_max_m are no returns (m).
  float range_min_m = 0.0f;
  float range_max_m = 0.0f;
  /// Per beam, angle counter-clockwise from the sensor's +x axis (rad).
  std::vector<float> angles_rad;
  /// Per beam (m); non-finite = no return.
  std::vector<float> ranges_m;
  /// Raw intensities in the scanner's counts, one per beam, or empty.
  std::vector<float> intensities;
};

}  // namespace rmap::slam2d
