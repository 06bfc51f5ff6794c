#include "sim/revisit.h"

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

namespace rmap::sim {
namespace {

/// A piece of the rounded path: a straight segment or a left arc.
struct PathPiece {
  Eigen::Vector2d start;
  double heading_rad;  ///< at the start
  double length_m;
  double curvature;    ///< 1/m, 0 for straight pieces
};

double wrapAngle(double a) { return std::remainder(a, 2.0 * std::numbers::pi); }

std::vector<PathPiece> roundedPath(const std::vector<Eigen::Vector2d>& corners, double radius) {
  const size_t n = corners.size();
  std::vector<double> tangent(n);  // cut back from each corner
  std::vector<double> turn(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d in = corners[i] - corners[(i + n - 1) % n], out = corners[(i + 1) % n] - corners[i];
    if (in.norm() < 1e-9 || out.norm() < 1e-9) throw std::invalid_argument("planRevisits: repeated corner");
    const double cross = in.x() * out.y() - in.y() * out.x();
    turn[i] = std::atan2(cross, in.dot(out));
    if (!(turn[i] > 1e-9)) throw std::invalid_argument("planRevisits: path must turn left (counter-clockwise) at every corner");
    tangent[i] = radius * std::tan(0.5 * turn[i]);
  }
  std::vector<PathPiece> pieces;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d a = corners[i], b = corners[(i + 1) % n];
    const double length = (b - a).norm();
    const double straight = length - tangent[i] - tangent[(i + 1) % n];
    if (straight < 0.0) throw std::invalid_argument("planRevisits: an edge is too short for corner_radius_m");
    const Eigen::Vector2d dir = (b - a) / length;
    const double heading = std::atan2(dir.y(), dir.x());
    pieces.push_back({a + tangent[i] * dir, heading, straight, 0.0});
    const double arc = radius * turn[(i + 1) % n];
    if (arc > 0.0) pieces.push_back({b - tangent[(i + 1) % n] * dir, heading, arc, 1.0 / radius});
  }
  return pieces;
}

/// Position and heading at arc length s (0 ≤ s < total) along the pieces.
void along(const std::vector<PathPiece>& pieces, double s, Eigen::Vector2d& p, double& heading) {
  for (const PathPiece& piece : pieces) {
    if (s > piece.length_m) {
      s -= piece.length_m;
      continue;
    }
    if (piece.curvature == 0.0) {
      p = piece.start + s * Eigen::Vector2d(std::cos(piece.heading_rad), std::sin(piece.heading_rad));
      heading = piece.heading_rad;
    } else {
      const double r = 1.0 / piece.curvature, a = s * piece.curvature;
      const Eigen::Vector2d left(-std::sin(piece.heading_rad), std::cos(piece.heading_rad));
      const Eigen::Vector2d center = piece.start + r * left;
      heading = piece.heading_rad + a;
      p = center - r * Eigen::Vector2d(-std::sin(heading), std::cos(heading));
    }
    return;
  }
  p = pieces.front().start;
  heading = pieces.front().heading_rad;
}

}  // namespace

void RevisitOptions::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("RevisitOptions: " + what); };
  if (laps < 1 || laps > 100) fail("laps must be in [1, 100]");
  if (!(step_m > 0.0) || !std::isfinite(step_m)) fail("step_m must be finite and > 0");
  if (!(corner_radius_m >= 0.0) || !std::isfinite(corner_radius_m)) fail("corner_radius_m must be finite and ≥ 0");
  if (!std::isfinite(sensor_height_m)) fail("sensor_height_m must be finite");
  if (!(lateral_offset_m >= 0.0) || !std::isfinite(lateral_offset_m)) fail("lateral_offset_m must be finite and ≥ 0");
  if (!(heading_jitter_rad >= 0.0 && heading_jitter_rad < 1.0)) fail("heading_jitter_rad must be in [0, 1)");
}

void LoopTruthOptions::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("LoopTruthOptions: " + what); };
  if (!(max_distance_m > 0.0) || !std::isfinite(max_distance_m)) fail("max_distance_m must be finite and > 0");
  if (!(max_heading_rad > 0.0) || !std::isfinite(max_heading_rad)) fail("max_heading_rad must be finite and > 0");
  if (!(min_travel_m >= 0.0) || !std::isfinite(min_travel_m)) fail("min_travel_m must be finite and ≥ 0");
}

std::vector<RevisitFrame> planRevisits(const std::vector<Eigen::Vector2d>& path_m, const RevisitOptions& options,
                                       uint64_t seed) {
  options.validate();
  if (path_m.size() < 3) throw std::invalid_argument("planRevisits: the path needs at least 3 corners");
  const std::vector<PathPiece> pieces = roundedPath(path_m, options.corner_radius_m);
  double lap_m = 0.0;
  for (const PathPiece& piece : pieces) lap_m += piece.length_m;
  if (lap_m > 1e6 * options.step_m / options.laps) throw std::invalid_argument("planRevisits: more than 10⁶ frames");

  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<double> phase(options.laps);
  for (double& p : phase) p = std::numbers::pi * unit(rng);
  constexpr double kWeave_m = 7.0;
  std::vector<RevisitFrame> frames;
  for (double travel = 0.0; travel < options.laps * lap_m; travel += options.step_m) {
    const int lap = std::min(options.laps - 1, static_cast<int>(travel / lap_m));
    const double s = travel - lap * lap_m;
    Eigen::Vector2d p;
    double heading;
    along(pieces, s, p, heading);
    const double offset = options.lateral_offset_m * std::sin(2.0 * std::numbers::pi * s / kWeave_m + phase[lap]);
    p += offset * Eigen::Vector2d(-std::sin(heading), std::cos(heading));
    heading += options.heading_jitter_rad * unit(rng);
    RevisitFrame frame;
    frame.pose_world = Eigen::Translation3d(p.x(), p.y(), options.sensor_height_m) *
                       Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ());
    frame.lap = lap;
    frame.travel_m = travel;
    frames.push_back(frame);
  }
  return frames;
}

std::vector<std::pair<int64_t, int64_t>> truthLoopPairs(const std::vector<RevisitFrame>& frames,
                                                        const LoopTruthOptions& options) {
  options.validate();
  auto heading = [](const RevisitFrame& f) {
    const Eigen::Vector3d x = f.pose_world.linear().col(0);
    return std::atan2(x.y(), x.x());
  };
  std::vector<std::pair<int64_t, int64_t>> pairs;
  for (size_t q = 0; q < frames.size(); ++q) {
    for (size_t r = 0; r < q; ++r) {
      if (frames[q].travel_m - frames[r].travel_m < options.min_travel_m) continue;
      const Eigen::Vector3d d = frames[q].pose_world.translation() - frames[r].pose_world.translation();
      if (d.head<2>().norm() > options.max_distance_m) continue;
      if (std::abs(wrapAngle(heading(frames[q]) - heading(frames[r]))) > options.max_heading_rad) continue;
      pairs.emplace_back(static_cast<int64_t>(q), static_cast<int64_t>(r));
    }
  }
  return pairs;
}

}  // namespace rmap::sim
