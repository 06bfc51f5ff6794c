#include "slam2d/calibration_eval.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <unordered_map>

#include "common/lidar_pair.h"
#include "datasets/ply_cloud.h"
#include "sim/building.h"
#include "sim/laser2d.h"
#include "sim/trajectory.h"
#include "slam2d/laser_scan.h"

namespace rmap::bench {
namespace {

constexpr double kUnmeasured = std::numeric_limits<double>::quiet_NaN();
constexpr double kDeg = std::numbers::pi / 180.0;

/// Value at quantile q ∈ [0, 1] (nearest rank); NaN for no values.
double quantile(std::vector<double> v, double q) {
  if (v.empty()) return kUnmeasured;
  auto at = v.begin() + static_cast<ptrdiff_t>(std::min(v.size() - 1.0, std::floor(q * v.size())));
  std::nth_element(v.begin(), at, v.end());
  return *at;
}

/// Coefficient of variation (population std / mean).
double variation(const std::vector<double>& v) {
  double mean = 0.0;
  for (double x : v) mean += x;
  mean /= v.size();
  double var = 0.0;
  for (double x : v) var += (x - mean) * (x - mean);
  return std::sqrt(var / v.size()) / mean;
}

/// Voxel of a point and its 63-bit key (21 bits per axis).
uint64_t voxelKey(const Eigen::Vector3d& p_m, double voxel_m) {
  uint64_t key = 0;
  for (int a = 0; a < 3; ++a) key = (key << 21) | (static_cast<uint64_t>(static_cast<int64_t>(std::floor(p_m[a] / voxel_m))) & 0x1FFFFF);
  return key;
}

uint64_t packCell(int64_t cx, int64_t cy) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(cx)) << 32) | static_cast<uint32_t>(cy);
}

/// One return of a simulated run with everything the scores need.
struct CalibrationReturn {
  uint64_t cell;
  float range_m;
  float cos_estimated;  ///< NaN without an estimate
  float cos_true;
  float intensity;
  float reflectivity;   ///< ground truth
};

std::vector<CalibrationReturn> simulateRun(const sim::Laser2dModel& model, uint64_t seed, const CalibrationEvalOptions& o,
                                   size_t& scans) {
  const sim::VoxelWorld world = sim::makeBuilding(sim::BuildingOptions{}, seed);
  sim::TrajectoryOptions tour;
  tour.num_poses = o.poses;
  tour.sensor_height_m = o.sensor_height_m;
  const std::vector<Eigen::Isometry3d> poses = sim::planTrajectory(world, tour, seed);
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + std::hash<std::string>{}(model.name));
  std::vector<CalibrationReturn> out;
  for (const Eigen::Isometry3d& pose : poses) {
    const sim::Laser2dScan sim_scan = sim::simulateLaser2d(world, pose, model, rng);
    slam2d::LaserScan scan;
    scan.model = sim_scan.model_name;
    scan.range_min_m = sim_scan.range_min_m;
    scan.range_max_m = sim_scan.range_max_m;
    scan.ranges_m = sim_scan.ranges_m;
    scan.intensities = sim_scan.intensities;
    for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
      scan.angles_rad.push_back(sim_scan.angle_min_rad + static_cast<float>(i) * sim_scan.angle_increment_rad);
    }
    const std::vector<float> cos_incidence = slam2d::cosIncidence(scan, o.incidence);
    for (size_t i = 0; i < scan.ranges_m.size(); ++i) {
      const float r = scan.ranges_m[i];
      if (!std::isfinite(r) || r < scan.range_min_m || r > scan.range_max_m) continue;
      const Eigen::Vector3d dir =
          (pose.linear() * Eigen::Vector3d(std::cos(scan.angles_rad[i]), std::sin(scan.angles_rad[i]), 0.0)).normalized();
      const std::optional<sim::RayHit> hit = world.castRay(pose.translation(), dir, model.max_range_m);
      if (!hit) continue;  // cannot happen for a return: the same ray found it
      const Eigen::Vector3d end = pose.translation() + r * dir;
      out.push_back({packCell(static_cast<int64_t>(std::floor(end.x() / o.cell_m)),
                              static_cast<int64_t>(std::floor(end.y() / o.cell_m))),
                     r, cos_incidence[i], static_cast<float>(std::abs(dir.dot(hit->normal))), scan.intensities[i],
                     sim_scan.reflectivities[i]});
    }
  }
  scans = poses.size();
  return out;
}

/// Reflectivity of every return under a calibration (NaN where it gives none).
std::vector<double> reflectivities(const slam2d::IntensityCalibration& cal, const std::vector<CalibrationReturn>& run) {
  std::vector<double> out;
  out.reserve(run.size());
  for (const CalibrationReturn& s : run) out.push_back(cal.reflectivity(s.intensity, s.range_m, s.cos_estimated));
  return out;
}

CalibrationScore score(const std::vector<double>& rho, const std::vector<CalibrationReturn>& run) {
  std::vector<double> rel;
  for (size_t j = 0; j < run.size(); ++j) {
    if (std::isfinite(rho[j])) rel.push_back(std::abs(rho[j] - run[j].reflectivity) / run[j].reflectivity);
  }
  return {quantile(rel, 0.5), quantile(rel, 0.9), run.empty() ? 0.0 : double(rel.size()) / run.size(), kUnmeasured};
}

/// Median over cells of the coefficient of variation of `value` per cell, on the returns `use` selects.
double medianCellVariation(const std::vector<CalibrationReturn>& run, const std::vector<char>& use,
                           const std::vector<double>& value, int min_views, size_t* cells) {
  std::unordered_map<uint64_t, std::vector<double>> per_cell;
  for (size_t j = 0; j < run.size(); ++j) {
    if (use[j]) per_cell[run[j].cell].push_back(value[j]);
  }
  std::vector<double> cv;
  for (const auto& [cell, v] : per_cell) {
    if (static_cast<int>(v.size()) >= min_views) cv.push_back(variation(v));
  }
  if (cells) *cells = cv.size();
  return quantile(cv, 0.5);
}

ScannerCalibrationEval evaluateScanner(const sim::Laser2dModel& model, const CalibrationEvalOptions& o) {
  ScannerCalibrationEval e;
  e.scanner = model.name;
  e.saturation_true = model.intensity.saturation;
  size_t scans = 0;
  const std::vector<CalibrationReturn> train = simulateRun(model, o.seed, o, scans);
  const std::vector<CalibrationReturn> test = simulateRun(model, o.seed + 1, o, e.scans);
  e.returns = test.size();

  std::vector<double> incidence_err;
  for (const CalibrationReturn& s : test) {
    if (std::isfinite(s.cos_estimated)) {
      incidence_err.push_back(std::abs(std::acos(std::min(1.0f, s.cos_estimated)) - std::acos(std::min(1.0f, s.cos_true))) / kDeg);
    }
  }
  e.incidence_err_deg_median = quantile(incidence_err, 0.5);
  e.incidence_coverage = test.empty() ? 0.0 : double(incidence_err.size()) / test.size();

  std::vector<slam2d::ReflectivityObservation> targets;
  for (const CalibrationReturn& s : train) targets.push_back({s.reflectivity, s.range_m, s.cos_estimated, s.intensity});
  const slam2d::IntensityCalibration supervised = slam2d::fitCalibration(targets, o.supervised);
  e.saturation_detected = supervised.saturation();
  e.supervised_calibration = supervised.toText();

  std::vector<slam2d::IntensityObservation> map_readings;
  for (const CalibrationReturn& s : test) map_readings.push_back({s.cell, s.range_m, s.cos_estimated, s.intensity});
  // The reference target: the surface of known reflectivity seen most (each
  // surface of the building has its own reflectivity, so the value names it).
  std::unordered_map<float, std::vector<slam2d::ReflectivityObservation>> by_surface;
  for (const CalibrationReturn& s : test) {
    by_surface[s.reflectivity].push_back({s.reflectivity, s.range_m, s.cos_estimated, s.intensity});
  }
  const std::vector<slam2d::ReflectivityObservation>* reference = nullptr;
  for (const auto& [rho, returns] : by_surface) {
    if (!reference || returns.size() > reference->size()) reference = &returns;
  }
  const std::vector<slam2d::ReflectivityObservation>& reference_readings = *reference;
  e.reference_views = reference->size();
  e.reference_reflectivity = reference_readings[0].reflectivity;
  const slam2d::IntensityCalibration self_shape = slam2d::selfCalibrate(map_readings, o.self);
  const slam2d::IntensityCalibration self = self_shape.anchoredTo(reference_readings);
  e.self_calibration = self.toText();
  {
    std::vector<double> ratio;
    const std::vector<double> rho = reflectivities(self_shape, test);
    for (size_t j = 0; j < test.size(); ++j) {
      if (std::isfinite(rho[j]) && rho[j] > 0.0) ratio.push_back(test[j].reflectivity / rho[j]);
    }
    const double best_scale = quantile(ratio, 0.5);
    std::vector<double> best = rho;
    for (double& r : best) r *= best_scale;
    e.self_shape_rel_err_median = score(best, test).rel_err_median;
  }
  {
    std::vector<slam2d::ReflectivityObservation> true_targets;
    for (const CalibrationReturn& s : train) true_targets.push_back({s.reflectivity, s.range_m, s.cos_true, s.intensity});
    const slam2d::IntensityCalibration cal = slam2d::fitCalibration(true_targets, o.supervised);
    std::vector<double> rho;
    for (const CalibrationReturn& s : test) rho.push_back(cal.reflectivity(s.intensity, s.range_m, s.cos_true));
    e.supervised_true_incidence_rel_err_median = score(rho, test).rel_err_median;
  }

  const std::vector<double> rho_supervised = reflectivities(supervised, test);
  const std::vector<double> rho_self = reflectivities(self, test);
  e.supervised = score(rho_supervised, test);
  e.self = score(rho_self, test);
  std::vector<char> both(test.size());
  std::vector<double> raw(test.size());
  for (size_t j = 0; j < test.size(); ++j) {
    both[j] = std::isfinite(rho_supervised[j]) && std::isfinite(rho_self[j]) && test[j].intensity > 0.0f;
    raw[j] = test[j].intensity;
  }
  e.spread_raw = medianCellVariation(test, both, raw, o.min_views, &e.spread_cells);
  e.supervised.spread = medianCellVariation(test, both, rho_supervised, o.min_views, nullptr);
  e.self.spread = medianCellVariation(test, both, rho_self, o.min_views, nullptr);
  return e;
}

/// Spearman's rank correlation.
double spearman(const std::vector<double>& a, const std::vector<double>& b) {
  auto ranks = [](const std::vector<double>& v) {
    std::vector<size_t> order(v.size());
    for (size_t i = 0; i < v.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](size_t x, size_t y) { return v[x] < v[y]; });
    std::vector<double> rank(v.size());
    for (size_t i = 0; i < order.size();) {  // ties share their mean rank
      size_t j = i;
      while (j + 1 < order.size() && v[order[j + 1]] == v[order[i]]) ++j;
      for (size_t k = i; k <= j; ++k) rank[order[k]] = 0.5 * (i + j);
      i = j + 1;
    }
    return rank;
  };
  const std::vector<double> ra = ranks(a), rb = ranks(b);
  const double n = a.size(), mean = 0.5 * (n - 1);
  double sab = 0, saa = 0, sbb = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    sab += (ra[i] - mean) * (rb[i] - mean);
    saa += (ra[i] - mean) * (ra[i] - mean);
    sbb += (rb[i] - mean) * (rb[i] - mean);
  }
  return sab / std::sqrt(saa * sbb);
}

/// Cosine of incidence per point from a plane through its neighbours within
/// a range-scaled radius (lidar rings spread apart with range); NaN where the
/// neighbourhood is not a plane or spans a single ring.
std::vector<float> lidarCosIncidence(const std::vector<Eigen::Vector3f>& points) {
  constexpr double kCell = 0.5;  // metres, hash cell; neighbours are searched within `reach` cells
  std::unordered_map<uint64_t, std::vector<uint32_t>> grid;
  for (uint32_t i = 0; i < points.size(); ++i) grid[voxelKey(points[i].cast<double>(), kCell)].push_back(i);
  std::vector<float> out(points.size(), std::numeric_limits<float>::quiet_NaN());
  std::vector<Eigen::Vector3d> near;
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d p = points[i].cast<double>();
    const double range = p.norm();
    const double radius = std::clamp(0.06 * range, 0.25, 1.0);
    const int reach = static_cast<int>(std::ceil(radius / kCell));
    near.clear();
    for (int dz = -reach; dz <= reach; ++dz) {
      for (int dy = -reach; dy <= reach; ++dy) {
        for (int dx = -reach; dx <= reach; ++dx) {
          const auto it = grid.find(voxelKey(p + kCell * Eigen::Vector3d(dx, dy, dz), kCell));
          if (it == grid.end()) continue;
          for (uint32_t k : it->second) {
            const Eigen::Vector3d q = points[k].cast<double>();
            if ((q - p).squaredNorm() <= radius * radius) near.push_back(q);
          }
        }
      }
    }
    if (near.size() < 8) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& q : near) mean += q;
    mean /= near.size();
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const Eigen::Vector3d& q : near) cov += (q - mean) * (q - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov / near.size());
    const Eigen::Vector3d l = eig.eigenvalues();  // ascending
    if (!(l(0) < 0.05 * l(1)) || !(l(1) > 0.05 * l(2))) continue;  // not flat, or one ring only
    out[i] = static_cast<float>(std::abs(eig.eigenvectors().col(0).dot(p / range)));
  }
  return out;
}

std::string fmt(double v, int digits = 3) {
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

}  // namespace

std::vector<ScannerCalibrationEval> evaluateSimulatedCalibration(const CalibrationEvalOptions& o) {
  if (o.poses < 1) throw std::invalid_argument("calibration eval: poses must be ≥ 1");
  if (!(o.cell_m > 0.0)) throw std::invalid_argument("calibration eval: cell_m must be > 0");
  if (o.min_views < 2) throw std::invalid_argument("calibration eval: min_views must be ≥ 2");
  return {evaluateScanner(sim::Laser2dModel::sickLike(), o), evaluateScanner(sim::Laser2dModel::hokuyoLike(), o)};
}

LidarIntensityCheck evaluateLidarPair(const std::string& dir, const CalibrationEvalOptions& o) {
  constexpr double kVoxel = 0.25;  // metres: a surface patch, both scans' points compared within it
  const Eigen::Matrix4d target_from_source = readTransform(dir + "/T_target_source.txt");
  LidarIntensityCheck c;
  struct Point {
    uint64_t voxel;
    int scan;
    float range_m, cos_incidence, intensity;
  };
  std::vector<Point> planar;
  const char* names[2] = {"source.ply", "target.ply"};
  for (int s = 0; s < 2; ++s) {
    const std::string path = dir + "/" + names[s];
    const datasets::PlyCloud cloud = datasets::readPlyCloud(path);
    const std::vector<float>& intensity = intensityOf(cloud, path);
    std::vector<Eigen::Vector3f> points;
    std::vector<float> values;
    for (size_t i = 0; i < cloud.points_m.size(); ++i) {
      if (cloud.points_m[i].squaredNorm() > 0.0f) points.push_back(cloud.points_m[i]), values.push_back(intensity[i]);
    }
    c.points[s] = points.size();
    const std::vector<float> cos_incidence = lidarCosIncidence(points);
    for (size_t i = 0; i < points.size(); ++i) {
      if (!std::isfinite(cos_incidence[i])) continue;
      Eigen::Vector3d q = points[i].cast<double>();
      if (s == 0) q = (target_from_source * q.homogeneous()).head<3>();
      planar.push_back({voxelKey(q, kVoxel), s, points[i].norm(), cos_incidence[i], values[i]});
      ++c.planar_points[s];
    }
  }
  std::vector<double> range, cosine, raw;
  for (const Point& p : planar) range.push_back(p.range_m), cosine.push_back(p.cos_incidence), raw.push_back(p.intensity);
  c.spearman_range = spearman(raw, range);
  c.spearman_cos = spearman(raw, cosine);

  // Fit on even voxels, score on odd ones (a hash, so both halves cover the scene).
  auto held_out = [](uint64_t voxel) { return (voxel * 0x9E3779B97F4A7C15ull) >> 63; };
  std::vector<slam2d::IntensityObservation> fit_set;
  for (const Point& p : planar) {
    if (!held_out(p.voxel)) fit_set.push_back({p.voxel, p.range_m, p.cos_incidence, p.intensity});
  }
  const slam2d::IntensityCalibration cal = slam2d::selfCalibrate(fit_set, o.self);
  const double r10 = quantile(range, 0.1), r50 = quantile(range, 0.5), r90 = quantile(range, 0.9);
  c.response_range_ratio = cal.response(r10, 1.0) / cal.response(r90, 1.0);
  c.response_incidence_ratio = cal.response(r50, std::cos(60 * kDeg)) / cal.response(r50, 1.0);

  std::unordered_map<uint64_t, std::array<std::vector<double>, 4>> per_voxel;  // raw s0, raw s1, ρ s0, ρ s1
  size_t scored = 0, held = 0;
  for (const Point& p : planar) {
    if (!held_out(p.voxel)) continue;
    ++held;
    const double rho = cal.reflectivity(p.intensity, p.range_m, p.cos_incidence);
    if (!std::isfinite(rho) || !(p.intensity > 0.0f)) continue;
    ++scored;
    auto& v = per_voxel[p.voxel];
    v[p.scan].push_back(p.intensity);
    v[2 + p.scan].push_back(rho);
  }
  c.coverage = held ? double(scored) / held : 0.0;
  auto mean = [](const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return s / v.size();
  };
  std::vector<double> between_raw, between_cal, within_raw, within_cal;
  for (const auto& [voxel, v] : per_voxel) {
    if (v[0].size() < 3 || v[1].size() < 3) continue;
    auto rel = [&](const std::vector<double>& a, const std::vector<double>& b) {
      return std::abs(mean(a) - mean(b)) / (0.5 * (mean(a) + mean(b)));
    };
    between_raw.push_back(rel(v[0], v[1]));
    between_cal.push_back(rel(v[2], v[3]));
    std::vector<double> raw_all = v[0], cal_all = v[2];
    raw_all.insert(raw_all.end(), v[1].begin(), v[1].end());
    cal_all.insert(cal_all.end(), v[3].begin(), v[3].end());
    within_raw.push_back(variation(raw_all));
    within_cal.push_back(variation(cal_all));
  }
  c.shared_cells = between_raw.size();
  c.between_scans_raw = quantile(between_raw, 0.5);
  c.between_scans_calibrated = quantile(between_cal, 0.5);
  c.within_cell_raw = quantile(within_raw, 0.5);
  c.within_cell_calibrated = quantile(within_cal, 0.5);
  return c;
}

nlohmann::json toJson(const ScannerCalibrationEval& e) {
  auto method = [&](const CalibrationScore& s) {
    return nlohmann::json{{"reflectivity_rel_err_median", s.rel_err_median},
                          {"reflectivity_rel_err_p90", s.rel_err_p90},
                          {"coverage", s.coverage},
                          {"reflectivity_spread_calibrated", s.spread},
                          {"spread_ratio", e.spread_raw / s.spread}};
  };
  return {{"scanner", e.scanner},
          {"scans_per_run", e.scans},
          {"returns", e.returns},
          {"incidence_err_deg_median", e.incidence_err_deg_median},
          {"incidence_coverage", e.incidence_coverage},
          {"saturation_true", e.saturation_true},
          {"saturation_detected", std::isfinite(e.saturation_detected) ? nlohmann::json(e.saturation_detected) : nlohmann::json()},
          {"reflectivity_spread_raw", e.spread_raw},
          {"spread_cells", e.spread_cells},
          {"supervised", method(e.supervised)},
          {"self", method(e.self)},
          {"supervised_true_incidence_rel_err_median", e.supervised_true_incidence_rel_err_median},
          {"self_shape_rel_err_median", e.self_shape_rel_err_median},
          {"self_reference_views", e.reference_views},
          {"self_reference_reflectivity", e.reference_reflectivity},
          {"supervised_calibration", e.supervised_calibration},
          {"self_calibration", e.self_calibration}};
}

nlohmann::json toJson(const LidarIntensityCheck& c) {
  return {{"points", {c.points[0], c.points[1]}},
          {"planar_points", {c.planar_points[0], c.planar_points[1]}},
          {"spearman_intensity_range", c.spearman_range},
          {"spearman_intensity_cos_incidence", c.spearman_cos},
          {"response_range_ratio_p10_p90", c.response_range_ratio},
          {"response_incidence_ratio_60deg", c.response_incidence_ratio},
          {"shared_voxels", c.shared_cells},
          {"between_scans_rel_diff_raw", c.between_scans_raw},
          {"between_scans_rel_diff_calibrated", c.between_scans_calibrated},
          {"within_voxel_spread_raw", c.within_cell_raw},
          {"within_voxel_spread_calibrated", c.within_cell_calibrated},
          {"coverage", c.coverage}};
}

int runCalibrationBench(const CalibrationEvalOptions& o) {
  nlohmann::json out{{"benchmark", "calib"}, {"poses", o.poses}, {"seed", o.seed}};
  const std::vector<ScannerCalibrationEval> sims = evaluateSimulatedCalibration(o);
  std::cout << "scanner      method      rel_err_med  rel_err_p90  coverage  spread (raw → calibrated, ratio)\n";
  for (const ScannerCalibrationEval& e : sims) {
    for (const auto& [name, s] : {std::pair{"supervised", e.supervised}, std::pair{"self", e.self}}) {
      std::printf("%-12s %-11s %11s  %11s  %8s  %s → %s (%s×)\n", e.scanner.c_str(), name, fmt(s.rel_err_median, 4).c_str(),
                  fmt(s.rel_err_p90, 4).c_str(), fmt(s.coverage).c_str(), fmt(e.spread_raw).c_str(),
                  fmt(s.spread, 4).c_str(), fmt(e.spread_raw / s.spread, 1).c_str());
    }
    std::printf("%-12s returns %zu, spread over %zu cells, incidence error median %s° (%s estimated), saturation %s detected at %s\n",
                e.scanner.c_str(), e.returns, e.spread_cells, fmt(e.incidence_err_deg_median, 2).c_str(),
                fmt(e.incidence_coverage).c_str(), fmt(e.saturation_true, 0).c_str(), fmt(e.saturation_detected, 0).c_str());
    std::printf("%-12s supervised with true incidence %s; self after the best global scale %s (reference surface: %zu returns, ρ %s)\n",
                e.scanner.c_str(), fmt(e.supervised_true_incidence_rel_err_median, 4).c_str(),
                fmt(e.self_shape_rel_err_median, 4).c_str(), e.reference_views, fmt(e.reference_reflectivity).c_str());
    out["scanners"].push_back(toJson(e));
  }
  if (!o.lidar_pair_dir.empty()) {
    const LidarIntensityCheck c = evaluateLidarPair(o.lidar_pair_dir, o);
    std::printf("lidar pair: %zu + %zu returns, %zu + %zu with a plane; Spearman(I, r) %s, Spearman(I, cos α) %s\n",
                c.points[0], c.points[1], c.planar_points[0], c.planar_points[1], fmt(c.spearman_range).c_str(),
                fmt(c.spearman_cos).c_str());
    std::printf("  self-calibrated g: r10/r90 ratio %s, 60°/0° ratio %s; held-out voxels in both scans %zu (coverage %s)\n",
                fmt(c.response_range_ratio).c_str(), fmt(c.response_incidence_ratio).c_str(), c.shared_cells,
                fmt(c.coverage).c_str());
    std::printf("  between scans |Δmean|/mean: raw %s → calibrated %s; within voxel CV: raw %s → calibrated %s\n",
                fmt(c.between_scans_raw).c_str(), fmt(c.between_scans_calibrated).c_str(), fmt(c.within_cell_raw).c_str(),
                fmt(c.within_cell_calibrated).c_str());
    out["lidar_pair"] = toJson(c);
  }
  if (!o.json_out.empty()) {
    std::ofstream f(o.json_out);
    f << out.dump(2) << "\n";
    if (!f) throw std::runtime_error("cannot write " + o.json_out);
  }
  return 0;
}

}  // namespace rmap::bench
