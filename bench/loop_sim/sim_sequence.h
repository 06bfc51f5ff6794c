#pragma once
/// @file sim_sequence.h
/// Simulated revisit sequences for place recognition: a carrier drives the
/// laps of a loop course (sim/loop_course.h, sim/revisit.h) and each frame is
/// a camera image or a laser-intensity scan (and its panorama), with the
/// ground-truth loop pairs from the true poses.
///
/// Lighting: the first lap is lit by `first_lap`; later laps by `revisit`
/// (other light level and direction), or, in a dark run, by `revisit` with
/// light_level = dark_light_level (sensor noise only). Laser intensities do not
/// depend on light. Every frame draws its noise from its own generator seeded
/// with (seed, frame, sensor), so frames can be made in any order and a seed
/// fixes the whole sequence.

#include <Eigen/Core>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "loop/loop_scoring.h"
#include "loop/panorama.h"
#include "sim/camera.h"
#include "sim/lidar.h"
#include "sim/loop_course.h"
#include "sim/revisit.h"

namespace rmap::bench {

struct SimSequenceOptions {
  uint64_t seed = 1;
  sim::LoopCourseOptions course;
  sim::RevisitOptions revisit;
  sim::LoopTruthOptions truth;
  sim::CameraModel camera;
  sim::Lighting first_lap;
  sim::Lighting revisit_lighting = changedLighting();
  bool dark = false;
  double dark_light_level = 0.02;
  sim::LidarModel lidar;

  /// Dimmer (60 %) and from another side than the default Lighting.
  static sim::Lighting changedLighting();
};

/// A lidar scan in the sensor frame.
struct SensorScan {
  std::vector<Eigen::Vector3f> points_sensor;
  std::vector<float> intensities;
};

class SimRevisitSequence {
 public:
  /// Builds the course and plans the laps. @throws std::invalid_argument for bad options
  explicit SimRevisitSequence(const SimSequenceOptions& options);

  size_t size() const { return frames_.size(); }
  const std::vector<sim::RevisitFrame>& frames() const { return frames_; }
  const LoopGroundTruth& truth() const { return truth_; }
  const sim::LoopCourse& course() const { return course_; }
  const SimSequenceOptions& options() const { return options_; }

  /// Camera image of frame i (camera at the sensor pose). @throws std::out_of_range
  cv::Mat cameraImage(size_t i) const;
  /// Lidar scan of frame i. @throws std::out_of_range
  SensorScan lidarScan(size_t i) const;

 private:
  SimSequenceOptions options_;
  sim::LoopCourse course_;
  std::vector<sim::RevisitFrame> frames_;
  LoopGroundTruth truth_;
};

}  // namespace rmap::bench
