#include "loop_sim/sim_sequence.h"

#include <random>
#include <stdexcept>
#include <string>

namespace rmap::bench {
namespace {

/// Independent generator per (seed, frame, sensor): splitmix-style mixing.
std::mt19937_64 frameRng(uint64_t seed, size_t frame, uint64_t sensor) {
  std::seed_seq seq{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32), static_cast<uint32_t>(frame),
                    static_cast<uint32_t>(frame >> 32), static_cast<uint32_t>(sensor)};
  return std::mt19937_64(seq);
}

void checkFrame(size_t i, size_t n) {
  if (i >= n) throw std::out_of_range("SimRevisitSequence: frame " + std::to_string(i) + " of " + std::to_string(n));
}

}  // namespace

sim::Lighting SimSequenceOptions::changedLighting() {
  sim::Lighting l;
  l.light_level = 0.6;
  l.light_direction = Eigen::Vector3d(0.5, 0.3, -0.8);
  l.ambient = 0.3;
  return l;
}

SimRevisitSequence::SimRevisitSequence(const SimSequenceOptions& options)
    : options_(options), course_(sim::makeLoopCourse(options.course, options.seed)) {
  options_.camera.validate();
  options_.first_lap.validate();
  options_.revisit_lighting.validate();
  options_.lidar.validate();
  if (!(options_.dark_light_level >= 0.0)) throw std::invalid_argument("SimSequenceOptions: dark_light_level must be ≥ 0");
  frames_ = sim::planRevisits(course_.centerline_m, options_.revisit, options_.seed);
  for (const auto& [q, r] : sim::truthLoopPairs(frames_, options_.truth)) truth_[q].insert(r);
}

cv::Mat SimRevisitSequence::cameraImage(size_t i) const {
  checkFrame(i, frames_.size());
  sim::Lighting light = frames_[i].lap == 0 ? options_.first_lap : options_.revisit_lighting;
  if (frames_[i].lap > 0 && options_.dark) light.light_level = options_.dark_light_level;
  std::mt19937_64 rng = frameRng(options_.seed, i, 1);
  const sim::GreyImage image = sim::renderCamera(course_.world, frames_[i].pose_world, options_.camera, light, rng);
  return cv::Mat(image.height, image.width, CV_8UC1, const_cast<uint8_t*>(image.pixels.data())).clone();
}

SensorScan SimRevisitSequence::lidarScan(size_t i) const {
  checkFrame(i, frames_.size());
  std::mt19937_64 rng = frameRng(options_.seed, i, 2);
  const sim::LidarScan scan = sim::simulateLidar(course_.world, frames_[i].pose_world, options_.lidar, rng);
  const Eigen::Isometry3f world_to_sensor = frames_[i].pose_world.inverse().cast<float>();
  SensorScan out;
  out.points_sensor.reserve(scan.points_m.size());
  for (const Eigen::Vector3f& p : scan.points_m) out.points_sensor.push_back(world_to_sensor * p);
  out.intensities = scan.intensities;
  return out;
}

}  // namespace rmap::bench
