#include "slam2d/slam2d_dataset.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

#include "datasets/carmen_log.h"
#include "sim/building.h"
#include "sim/laser2d.h"
#include "sim/trajectory.h"

namespace rmap::bench {
namespace {

using slam2d::Pose2;

constexpr int64_t kSimScanPeriodNs = 100'000'000;  // 10 Hz
constexpr double kSimStepM = 0.1;                  // path poses 0.1 m apart: 1 m/s at 10 Hz
constexpr double kSimMaxTurnRad = 5.0 * std::numbers::pi / 180.0;

std::optional<double> spanOfStamps(std::vector<int64_t> stamps) {
  if (stamps.size() < 2) return std::nullopt;
  std::sort(stamps.begin(), stamps.end());
  if (stamps.front() == stamps.back()) return std::nullopt;
  for (size_t i = 1; i < stamps.size(); ++i) {
    if (stamps[i] - stamps[i - 1] > 600'000'000'000) return std::nullopt;
  }
  return double(stamps.back() - stamps.front()) * 1e-9;
}

/// See Slam2dDataset::scans_numbered.
void numberScansWithoutStamps(Slam2dDataset& data) {
  std::unordered_set<int64_t> distinct;
  for (const Slam2dInput& in : data.inputs) distinct.insert(in.scan.stamp_ns);
  if (2 * distinct.size() >= data.inputs.size()) return;
  for (size_t k = 0; k < data.inputs.size(); ++k) data.inputs[k].scan.stamp_ns = static_cast<int64_t>(k);
  data.scans_numbered = true;
}

Slam2dDataset fromLog(const std::string& path, OdometrySource odometry) {
  datasets::CarmenLog log = datasets::readCarmenLog(path);
  if (log.scans.empty()) throw std::runtime_error(path + ": no FLASER or ROBOTLASER1 scans");
  Slam2dDataset data;
  data.name = std::filesystem::path(path).filename().string();
  const bool restarts = datasets::odometryRestartsAtScans(log);
  data.reference_kind = restarts               ? "corrected poses of the log"
                        : !log.odometry.empty() ? "raw odometry of the log"
                                                : "poses of the log (no ODOM lines tell raw from corrected)";
  if (odometry == OdometrySource::kAuto) {
    odometry = restarts                 ? OdometrySource::kOdomIncrements
               : log.odometry.empty()   ? OdometrySource::kNone
                                        : OdometrySource::kLogged;
  }
  if (odometry == OdometrySource::kOdomIncrements && log.odometry.empty()) {
    throw std::runtime_error(path + ": odometry from ODOM increments asked for, but the log has no ODOM lines");
  }
  if (odometry == OdometrySource::kLogged && restarts) {
    throw std::runtime_error(path + ": its ODOM lines restart at every scan pose, so the logged poses are corrected "
                             "(the reference), not odometry; use odom-increments or none");
  }
  std::vector<std::optional<Pose2>> increments;
  if (odometry == OdometrySource::kOdomIncrements) increments = datasets::odometryFromOdomIncrements(log);
  data.odometry_kind = odometry == OdometrySource::kOdomIncrements ? "increments of the ODOM lines"
                       : odometry == OdometrySource::kLogged       ? "logged robot poses (raw odometry)"
                                                                   : "none";
  std::vector<int64_t> stamps;
  data.inputs.reserve(log.scans.size());
  for (size_t k = 0; k < log.scans.size(); ++k) {
    datasets::CarmenScan& s = log.scans[k];
    std::optional<Pose2> odo;
    if (odometry == OdometrySource::kLogged) odo = s.robot_pose;
    if (odometry == OdometrySource::kOdomIncrements) odo = increments[k];
    stamps.push_back(s.scan.stamp_ns);
    data.reference.push_back(s.laser_pose);
    data.inputs.push_back({std::move(s.scan), odo});
  }
  data.duration_s = spanOfStamps(std::move(stamps));
  for (const auto& [name, count] : log.skipped) data.skipped_lines += count;
  return data;
}

Pose2 planar(const Eigen::Isometry3d& pose) {
  const Eigen::Vector3d x = pose.linear().col(0);
  return {pose.translation().x(), pose.translation().y(), std::atan2(x.y(), x.x())};
}

/// The tour as planar sensor poses, with turns on the spot of at most kSimMaxTurnRad per pose.
std::vector<Pose2> simTour(const sim::VoxelWorld& world, const Slam2dSimOptions& o, double sensor_height_m) {
  sim::TrajectoryOptions traj;
  traj.num_poses = o.poses;
  traj.sensor_height_m = sensor_height_m;
  traj.max_step_m = 0.05;  // one storey, no stairs: allows short steps
  traj.step_m = kSimStepM;
  std::vector<Pose2> tour;
  for (const Eigen::Isometry3d& p : sim::planTrajectory(world, traj, o.seed)) {
    const Pose2 next = planar(p);
    if (!tour.empty()) {
      const Pose2 last = tour.back();
      const double turn = slam2d::normalizeAngle(next.theta_rad - last.theta_rad);
      const int steps = int(std::ceil(std::abs(turn) / kSimMaxTurnRad));
      for (int i = 1; i < steps; ++i) tour.push_back({last.x_m, last.y_m, slam2d::normalizeAngle(last.theta_rad + turn * i / steps)});
    }
    tour.push_back(next);
  }
  return tour;
}

Slam2dDataset simulateBuilding(const Slam2dSimOptions& o) {
  sim::Laser2dModel laser;
  if (o.laser == "sick") {
    laser = sim::Laser2dModel::sickLike();
  } else if (o.laser == "hokuyo") {
    laser = sim::Laser2dModel::hokuyoLike();
  } else {
    throw std::runtime_error("unknown simulated laser \"" + o.laser + "\" (sick or hokuyo)");
  }
  const sim::VoxelWorld world = sim::makeBuilding(sim::BuildingOptions{}, o.seed);
  constexpr double kSensorHeightM = 0.5;
  const std::vector<Pose2> tour = simTour(world, o, kSensorHeightM);

  Slam2dDataset data;
  data.name = "sim:building (" + laser.name + ", " + std::to_string(tour.size()) + " scans)";
  data.simulated = true;
  data.reference_kind = "simulation truth";
  data.odometry_kind = "true motion with 1 % scale bias and random errors";
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> unit(0.0, 1.0);
  Pose2 odometry;
  for (size_t k = 0; k < tour.size(); ++k) {
    if (k > 0) {
      // Wheel odometry: a scale bias plus errors growing with the motion.
      const Pose2 d = slam2d::between(tour[k - 1], tour[k]);
      const double dist = d.translation().norm(), turn = std::abs(d.theta_rad);
      const Pose2 noisy{d.x_m * 1.01 + unit(rng) * 0.02 * dist, d.y_m + unit(rng) * 0.01 * dist,
                        d.theta_rad * 1.01 + unit(rng) * (0.02 * turn + 0.01 * dist)};
      odometry = odometry * noisy;
    }
    const Eigen::Isometry3d sensor = Eigen::Translation3d(tour[k].x_m, tour[k].y_m, kSensorHeightM) *
                                     Eigen::AngleAxisd(tour[k].theta_rad, Eigen::Vector3d::UnitZ());
    sim::Laser2dScan s = sim::simulateLaser2d(world, sensor, laser, rng);
    slam2d::LaserScan scan;
    scan.stamp_ns = int64_t(k) * kSimScanPeriodNs;
    scan.model = s.model_name;
    scan.range_min_m = s.range_min_m;
    scan.range_max_m = s.range_max_m;
    scan.angles_rad.resize(s.ranges_m.size());
    for (size_t i = 0; i < s.ranges_m.size(); ++i) {
      scan.angles_rad[i] = s.angle_min_rad + float(i) * s.angle_increment_rad;
      if (std::isfinite(s.ranges_m[i])) data.sim_returns.push_back({uint32_t(k), uint32_t(i), s.reflectivities[i]});
    }
    scan.ranges_m = std::move(s.ranges_m);
    scan.intensities = std::move(s.intensities);
    data.inputs.push_back({std::move(scan), odometry});
    data.reference.push_back(tour[k]);
  }
  data.duration_s = double(tour.size() - 1) * kSimScanPeriodNs * 1e-9;
  // Ground-truth relations like Kümmerle's: each scan to the ones 1 s and 10 s later.
  for (size_t k = 0; k < tour.size(); ++k) {
    for (size_t later : {k + 10, k + 100}) {
      if (later >= tour.size()) continue;
      data.relations.push_back({data.inputs[k].scan.stamp_ns, data.inputs[later].scan.stamp_ns,
                                slam2d::between(tour[k], tour[later]), 0});
    }
  }
  return data;
}

/// The ranges of a scan to the millimetre; readings at or beyond `cut` (and
/// non-finite ones) alike, so two logs whose no-return ranges differ agree.
std::vector<int32_t> rangeKey(const slam2d::LaserScan& scan, float cut) {
  std::vector<int32_t> key(scan.ranges_m.size());
  for (size_t i = 0; i < key.size(); ++i) {
    const float r = scan.ranges_m[i];
    key[i] = std::isfinite(r) && r < cut ? int32_t(std::lround(double(r) * 1000.0)) : -1;
  }
  return key;
}

struct RangeKeyHash {
  size_t operator()(const std::vector<int32_t>& key) const {
    uint64_t h = 1469598103934665603ull;  // FNV-1a over the values
    for (int32_t v : key) h = (h ^ uint32_t(v)) * 1099511628211ull;
    return size_t(h);
  }
};

/// Gives each scan found (by its ranges) in the log at `path` that log's
/// stamp; scans that appear there more than once (a robot standing still)
/// keep theirs.
void takeStampsFrom(Slam2dDataset& data, const std::string& path) {
  const datasets::CarmenLog log = datasets::readCarmenLog(path);
  float cut = std::numeric_limits<float>::infinity();
  for (const datasets::CarmenScan& s : log.scans) cut = std::min(cut, s.scan.range_max_m);
  for (const Slam2dInput& in : data.inputs) cut = std::min(cut, in.scan.range_max_m);
  constexpr int64_t kAmbiguous = std::numeric_limits<int64_t>::min();
  std::unordered_map<std::vector<int32_t>, int64_t, RangeKeyHash> stamps;
  for (const datasets::CarmenScan& s : log.scans) {
    const auto [it, inserted] = stamps.emplace(rangeKey(s.scan, cut), s.scan.stamp_ns);
    if (!inserted) it->second = kAmbiguous;
  }
  for (Slam2dInput& in : data.inputs) {
    const auto it = stamps.find(rangeKey(in.scan, cut));
    if (it == stamps.end() || it->second == kAmbiguous) continue;
    in.scan.stamp_ns = it->second;
    ++data.stamps_replaced;
  }
  if (data.stamps_replaced == 0) throw std::runtime_error(path + ": holds none of the log's scans, no stamps to take");
  std::vector<int64_t> all;
  for (const Slam2dInput& in : data.inputs) all.push_back(in.scan.stamp_ns);
  data.duration_s = spanOfStamps(std::move(all));
}

/// Replaces the reference with the laser poses of `path` at equal stamps.
void useReferenceLog(Slam2dDataset& data, const std::string& path) {
  const datasets::CarmenLog log = datasets::readCarmenLog(path);
  std::unordered_map<int64_t, Pose2> poses;
  for (const datasets::CarmenScan& s : log.scans) poses.emplace(s.scan.stamp_ns, s.laser_pose);
  size_t matched = 0;
  for (size_t k = 0; k < data.inputs.size(); ++k) {
    const auto it = poses.find(data.inputs[k].scan.stamp_ns);
    data.reference[k] = it == poses.end() ? std::nullopt : std::optional<Pose2>(it->second);
    matched += it != poses.end();
  }
  if (matched == 0) throw std::runtime_error(path + ": no scan stamp in common with the log, cannot be its reference");
  data.reference_kind = "poses of " + std::filesystem::path(path).filename().string() + " at " +
                        std::to_string(matched) + " shared stamps";
}

}  // namespace

size_t placeRelationsByScanPeriod(std::vector<datasets::SlamRelation>& relations,
                                  const std::vector<Slam2dInput>& inputs, double period_s, size_t first_scan) {
  if (!(period_s > 0.0) || !std::isfinite(period_s))
    throw std::invalid_argument("relations' scan period must be positive and finite");
  std::vector<int64_t> stamps;
  for (const datasets::SlamRelation& r : relations) stamps.insert(stamps.end(), {r.from_stamp_ns, r.to_stamp_ns});
  std::sort(stamps.begin(), stamps.end());
  stamps.erase(std::unique(stamps.begin(), stamps.end()), stamps.end());
  // Each gap on its own: the period drifts a little over a long log, so one
  // division from the first stamp would slip by whole scans where the gaps do not.
  std::unordered_map<int64_t, size_t> scan_of;
  size_t scan = first_scan;
  for (size_t i = 0; i < stamps.size(); ++i) {
    if (i > 0) {
      const double periods = double(stamps[i] - stamps[i - 1]) * 1e-9 / period_s;
      const double whole = std::round(periods);
      if (whole < 1.0 || std::abs(periods - whole) > 0.3)
        throw std::invalid_argument("relation stamps " + std::to_string(stamps[i - 1]) + " and " +
                                    std::to_string(stamps[i]) + " ns lie " + std::to_string(periods) +
                                    " scan periods apart, not a whole number: not the relations' scan period");
      scan += static_cast<size_t>(whole);
    }
    scan_of.emplace(stamps[i], scan);
  }
  const size_t before = relations.size();
  std::erase_if(relations, [&](datasets::SlamRelation& r) {
    const size_t from = scan_of.at(r.from_stamp_ns), to = scan_of.at(r.to_stamp_ns);
    if (from >= inputs.size() || to >= inputs.size()) return true;
    r.from_stamp_ns = inputs[from].scan.stamp_ns;
    r.to_stamp_ns = inputs[to].scan.stamp_ns;
    return false;
  });
  return before - relations.size();
}

OdometrySource parseOdometrySource(const std::string& name) {
  if (name == "auto") return OdometrySource::kAuto;
  if (name == "logged") return OdometrySource::kLogged;
  if (name == "odom-increments") return OdometrySource::kOdomIncrements;
  if (name == "none") return OdometrySource::kNone;
  throw std::invalid_argument("odometry source must be auto, logged, odom-increments or none, not \"" + name + "\"");
}

Slam2dDataset loadSlam2dDataset(const std::string& source, const Slam2dSourceOptions& options) {
  Slam2dDataset data;
  if (source == "sim:building") {
    data = simulateBuilding(options.sim);
    if (options.odometry == OdometrySource::kNone) {
      for (Slam2dInput& in : data.inputs) in.odometry.reset();
      data.odometry_kind = "none";
    }
  } else if (source.rfind("sim:", 0) == 0) {
    throw std::runtime_error("unknown simulated source " + source + " (sim:building)");
  } else {
    if (!std::filesystem::exists(source)) throw std::runtime_error(source + ": no such file");
    data = fromLog(source, options.odometry);
  }
  if (!options.stamps_path.empty()) takeStampsFrom(data, options.stamps_path);
  if (!options.reference_path.empty()) useReferenceLog(data, options.reference_path);
  // Only when no other log is to be matched by stamp: its scans would not carry the numbers.
  if (options.stamps_path.empty() && options.reference_path.empty()) numberScansWithoutStamps(data);
  if (!options.relations_path.empty()) {
    data.relations = datasets::readSlamRelations(options.relations_path);
    if (options.relations_scan_period_s > 0.0)
      data.relations_dropped = placeRelationsByScanPeriod(data.relations, data.inputs, options.relations_scan_period_s,
                                                          options.relations_first_scan);
  }
  return data;
}

}  // namespace rmap::bench
