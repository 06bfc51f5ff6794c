#include "slam2d/slam2d_bench.h"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <unordered_map>

#include "common/machine.h"
#include "slam2d/reflectivity_metrics.h"
#include "slam2d/trajectory_metrics.h"

namespace rmap::bench {
namespace {

using json = nlohmann::json;
using slam2d::Pose2;

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

double processCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

struct SlamRun {
  std::vector<Pose2> laser_poses;  ///< estimated sensor pose per scan
  std::vector<Pose2> robot_poses;  ///< estimated base pose per scan
  size_t rejected = 0, non_finite = 0, outside_map = 0;
  std::string first_rejection;
  double wall_s = 0.0, cpu_s = 0.0;
};

SlamRun runSlam(slam2d::Slam2d& slam, const std::vector<Slam2dInput>& inputs) {
  SlamRun run;
  run.laser_poses.reserve(inputs.size());
  run.robot_poses.reserve(inputs.size());
  const double cpu0 = processCpuSeconds();
  const auto t0 = std::chrono::steady_clock::now();
  for (const Slam2dInput& in : inputs) {
    Pose2 robot;
    try {
      robot = slam.addScan("robot", in.scan, in.odometry);
    } catch (const std::invalid_argument& e) {
      if (run.rejected++ == 0) run.first_rejection = e.what();
      robot = slam.pose("robot").value_or(Pose2{});
    }
    run.robot_poses.push_back(robot);
    run.laser_poses.push_back(robot * in.scan.sensor_mount);
  }
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  run.cpu_s = processCpuSeconds() - cpu0;
  if (slam.options().loop_closure.enabled) {
    // Scored: the final corrected trajectory (every scan on its corrected keyframe).
    const std::vector<slam2d::StampedPose2> corrected = slam.trajectory("robot");
    size_t k = 0;
    for (size_t i = 0; i < inputs.size() && k < corrected.size(); ++i) {
      if (corrected[k].stamp_ns != inputs[i].scan.stamp_ns) continue;  // a rejected scan has no pose of its own
      run.robot_poses[i] = corrected[k].pose;
      run.laser_poses[i] = corrected[k].pose * inputs[i].scan.sensor_mount;
      ++k;
    }
  }
  const Eigen::AlignedBox2i known = slam.grid().knownCells();
  for (const Pose2& p : run.robot_poses) {
    if (!p.isFinite()) {
      ++run.non_finite;
    } else if (!known.contains(slam.grid().cellOf(p.translation()))) {
      ++run.outside_map;
    }
  }
  return run;
}

json statsJson(const ErrorStats& s, double scale = 1.0) {
  return {{"mean", s.mean * scale}, {"std", s.std * scale}, {"rmse", s.rmse * scale}, {"max", s.max * scale}};
}

std::vector<StampedPose2> stamped(const std::vector<Slam2dInput>& inputs, const std::vector<Pose2>& poses) {
  std::vector<StampedPose2> out(poses.size());
  for (size_t i = 0; i < poses.size(); ++i) out[i] = {inputs[i].scan.stamp_ns, poses[i]};
  return out;
}

json slamOptionsJson(const slam2d::Slam2dOptions& o) {
  return {{"resolution_m", o.resolution_m},
          {"levels", o.levels},
          {"map_update_distance_m", o.map_update_distance_m},
          {"map_update_angle_rad", o.map_update_angle_rad},
          {"range_min_m", o.range_min_m},
          {"range_max_m", o.range_max_m},
          {"use_odometry", o.use_odometry},
          {"odometry_information_xy", o.odometry_information_xy},
          {"odometry_information_theta", o.odometry_information_theta},
          {"reflectivity_weight", o.reflectivity_weight}};
}

void writePoses(const std::string& path, const std::vector<Slam2dInput>& inputs, const std::vector<Pose2>& poses) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  char line[128];
  for (size_t i = 0; i < poses.size(); ++i) {
    std::snprintf(line, sizeof line, "%.6f %.6f %.6f %.6f\n", double(inputs[i].scan.stamp_ns) * 1e-9, poses[i].x_m,
                  poses[i].y_m, poses[i].theta_rad);
    out << line;
  }
}

/// The poses of `estimate` and `reference` where the reference is known.
struct Paired {
  std::vector<Pose2> estimate, reference;
  std::vector<StampedPose2> stamped_reference;
};

Paired paired(const std::vector<Slam2dInput>& inputs, const std::vector<Pose2>& estimate,
              const std::vector<std::optional<Pose2>>& reference) {
  Paired p;
  for (size_t i = 0; i < estimate.size(); ++i) {
    if (!reference[i]) continue;
    p.estimate.push_back(estimate[i]);
    p.reference.push_back(*reference[i]);
    p.stamped_reference.push_back({inputs[i].scan.stamp_ns, *reference[i]});
  }
  return p;
}

double orNan(const std::optional<double>& v) { return v.value_or(std::numeric_limits<double>::quiet_NaN()); }

/// The occupancy grid as an 8-bit image (ROS map_server shades: free 254, occupied 0, unknown 205),
/// north up, scaled down by area averaging so its longer side is at most max_px.
void writeMapImage(const std::string& path, const slam2d::GridMap2d& grid, int max_px) {
  const Eigen::AlignedBox2i box = grid.knownCells();
  if (box.isEmpty()) throw std::runtime_error("no map to write to " + path);
  const Eigen::Vector2i size = box.sizes() + Eigen::Vector2i::Ones();
  cv::Mat image(size.y(), size.x(), CV_8UC1);
  for (int y = 0; y < size.y(); ++y) {
    for (int x = 0; x < size.x(); ++x) {
      const float p = grid.probability(box.min() + Eigen::Vector2i(x, y));
      image.at<uint8_t>(size.y() - 1 - y, x) =
          std::isfinite(p) ? static_cast<uint8_t>(std::lround(254.0 * (1.0 - std::clamp(p, 0.0f, 1.0f)))) : 205;
    }
  }
  const double scale = std::min(1.0, double(max_px) / double(std::max(size.x(), size.y())));
  if (scale < 1.0) cv::resize(image, image, cv::Size(), scale, scale, cv::INTER_AREA);
  if (!cv::imwrite(path, image)) throw std::runtime_error("cannot write " + path);
}

/// Judges accepted loop closures against reference laser poses: a scan
/// without one borrows the nearest scan's that has one, carried over by the
/// estimated motion between the two (a few scans: centimetres).
struct ClosureJudge {
  std::vector<std::optional<Pose2>> reference;  ///< per input
  std::unordered_map<int64_t, size_t> index_of_stamp;
  static constexpr size_t kMaxBorrow = 30;      ///< scans searched each way for a reference pose
  static constexpr double kMaxError_m = 0.3, kMaxError_rad = 5.0 / kDegPerRad;

  std::optional<Pose2> referenceOf(int64_t stamp, const std::vector<Pose2>& estimate) const {
    const auto it = index_of_stamp.find(stamp);
    if (it == index_of_stamp.end()) return std::nullopt;
    const size_t i = it->second;
    for (size_t d = 0; d <= kMaxBorrow; ++d) {
      for (const size_t j : {i - d, i + d}) {
        if (j >= reference.size() || !reference[j]) continue;  // i − d wraps below 0 to a huge index
        return *reference[j] * between(estimate[j], estimate[i]);
      }
    }
    return std::nullopt;
  }
};

}  // namespace

int runSlam2dBench(const Slam2dBenchOptions& options) {
  std::cout << "loading " << options.source << " ..." << std::endl;
  Slam2dSourceOptions source;
  source.relations_path = options.relations_path;
  source.reference_path = options.reference_path;
  source.stamps_path = options.stamps_path;
  source.odometry = parseOdometrySource(options.odometry);
  source.sim = options.sim;
  Slam2dDataset data = loadSlam2dDataset(options.source, source);
  if (options.max_scans > 0 && data.inputs.size() > options.max_scans) {
    data.inputs.resize(options.max_scans);
    data.reference.resize(options.max_scans);
    std::erase_if(data.sim_returns, [&](const SimReturn& r) { return r.scan >= options.max_scans; });
    std::vector<int64_t> stamps;
    for (const Slam2dInput& in : data.inputs) stamps.push_back(in.scan.stamp_ns);
    const auto [lo, hi] = std::minmax_element(stamps.begin(), stamps.end());
    if (data.duration_s) data.duration_s = double(*hi - *lo) * 1e-9;
  }
  std::cout << data.name << ": " << data.inputs.size() << " scans, odometry: " << data.odometry_kind
            << ", reference: " << data.reference_kind << std::endl;

  slam2d::Slam2d slam(options.slam);
  const SlamRun run = runSlam(slam, data.inputs);
  const std::vector<slam2d::LoopClosure2d> closures = slam.takeLoopClosures();

  const RelationErrors rel = relationErrors(stamped(data.inputs, run.laser_poses), data.relations);
  const Paired scored = paired(data.inputs, run.laser_poses, data.reference);
  const ErrorStats ate = absoluteTrajectoryError(scored.estimate, scored.reference);
  const RelativePoseErrors rpe = relativePoseError(scored.estimate, scored.reference, options.rpe_distance_m);
  // NaN (null in the JSON) when the log's stamps do not measure time.
  const double realtime = orNan(data.duration_s) / run.wall_s;

  json r = {{"benchmark", "slam2d"},
            {"dataset", data.name},
            {"source", options.source},
            {"scans", data.inputs.size()},
            {"scans_rejected", run.rejected},
            {"non_finite_poses", run.non_finite},
            {"poses_outside_map", run.outside_map},
            {"odometry", data.odometry_kind},
            {"reference", data.reference_kind},
            {"reference_file", options.reference_path},
            {"reference_poses", scored.reference.size()},
            {"stamps_file", options.stamps_path},
            {"stamps_replaced", data.stamps_replaced},
            {"relations_file", options.relations_path},
            {"relations_total", data.relations.size()},
            {"relations_used", rel.relations_used},
            {"rel_trans_err_m", statsJson(rel.translation_m)},
            {"rel_rot_err_deg", statsJson(rel.rotation_rad, kDegPerRad)},
            {"ate_vs_reference_m", ate.rmse},
            {"rpe_1m_m", rpe.translation_m.rmse},
            {"rpe", {{"distance_m", options.rpe_distance_m},
                     {"pairs", rpe.translation_m.count},
                     {"trans_m", statsJson(rpe.translation_m)},
                     {"rot_deg", statsJson(rpe.rotation_rad, kDegPerRad)}}},
            {"log_duration_s", orNan(data.duration_s)},
            {"wall_s", run.wall_s},
            {"realtime_factor", realtime},
            {"cpu_s", run.cpu_s},
            // wall time suffers from other processes on a shared machine; CPU time much less
            {"realtime_factor_cpu", orNan(data.duration_s) / run.cpu_s},
            {"map", {{"resolution_m", slam.grid().resolution_m()},
                     {"known_cells", {slam.grid().knownCells().sizes().x(), slam.grid().knownCells().sizes().y()}},
                     {"updates", slam.version()}}},
            {"slam_options", slamOptionsJson(options.slam)},
            {"machine", machineJson()}};
  if (!run.first_rejection.empty()) r["first_rejection"] = run.first_rejection;
  if (const slam2d::LoopClosureStats* lc = slam.loopClosureStats()) {
    // Judge: a corrected log of the same run (scans found by their ranges), else the reference poses.
    ClosureJudge judge;
    // A closure names its scans by stamp: scans sharing a stamp (logs whose stamps were rounded) cannot be judged.
    constexpr size_t kShared = std::numeric_limits<size_t>::max();
    for (size_t i = 0; i < data.inputs.size(); ++i) {
      const auto [it, inserted] = judge.index_of_stamp.emplace(data.inputs[i].scan.stamp_ns, i);
      if (!inserted) it->second = kShared;
    }
    std::erase_if(judge.index_of_stamp, [&](const auto& entry) { return entry.second == kShared; });
    std::string judged_by = data.reference_kind;
    if (!options.closure_reference_path.empty()) {
      Slam2dSourceOptions ref_source;
      ref_source.stamps_path = options.source;
      ref_source.odometry = OdometrySource::kNone;
      const Slam2dDataset ref = loadSlam2dDataset(options.closure_reference_path, ref_source);
      judge.reference.assign(data.inputs.size(), std::nullopt);
      for (size_t k = 0; k < ref.inputs.size(); ++k) {
        const auto it = judge.index_of_stamp.find(ref.inputs[k].scan.stamp_ns);
        if (it != judge.index_of_stamp.end() && ref.reference[k]) judge.reference[it->second] = ref.reference[k];
      }
      judged_by = "poses of " + options.closure_reference_path + " (" + std::to_string(ref.stamps_replaced) +
                  " scans found)";
    } else if (data.reference_kind.find("raw odometry") == std::string::npos) {
      judge.reference = data.reference;
    } else {
      judged_by = "none (raw odometry is no reference)";
    }
    size_t judged = 0, false_closures = 0, cross = 0;
    double worst_m = 0.0;
    json list = json::array();
    for (const slam2d::LoopClosure2d& c : closures) {
      cross += c.query_trajectory != c.match_trajectory;
      const auto mount_it = judge.index_of_stamp.find(c.query_stamp_ns);
      const Pose2 mount = mount_it == judge.index_of_stamp.end() ? Pose2{} : data.inputs[mount_it->second].scan.sensor_mount;
      const Pose2 measured = mount.inverse() * c.relative * mount;  // laser to laser
      json item = {{"query_stamp_ns", c.query_stamp_ns}, {"match_stamp_ns", c.match_stamp_ns}, {"score", c.score},
                   {"relative", {c.relative.x_m, c.relative.y_m, c.relative.theta_rad}}};
      const std::optional<Pose2> rq = judge.referenceOf(c.query_stamp_ns, run.laser_poses);
      const std::optional<Pose2> rm = judge.referenceOf(c.match_stamp_ns, run.laser_poses);
      if (rq && rm) {
        const Pose2 e = between(between(*rm, *rq), measured);
        const bool wrong = e.translation().norm() > ClosureJudge::kMaxError_m ||
                           std::abs(e.theta_rad) > ClosureJudge::kMaxError_rad;
        ++judged;
        false_closures += wrong;
        worst_m = std::max(worst_m, e.translation().norm());
        item["error_m"] = e.translation().norm();
        item["error_deg"] = std::abs(e.theta_rad) * kDegPerRad;
        item["false"] = wrong;
      }
      list.push_back(item);
    }
    r["loop_closure"] = {{"closures", closures.size()},
                         {"cross_trajectory_closures", cross},
                         {"closures_judged", judged},
                         {"false_closures", judged > 0 ? json(false_closures) : json(nullptr)},
                         {"worst_closure_error_m", judged > 0 ? json(worst_m) : json(nullptr)},
                         {"judged_by", judged_by},
                         {"keyframes", slam.keyframeCount()},
                         {"searches", lc->searches},
                         {"matches", lc->matches},
                         {"ambiguous", lc->ambiguous},
                         {"accepted", lc->accepted},
                         {"unsupported", lc->unsupported},
                         {"rejected_after_optimization", lc->rejected_after_optimization},
                         {"optimizations", lc->optimizations},
                         {"graph_versions", slam.graphVersion()},
                         {"optimization_s", lc->optimization_s},
                         {"search_s", lc->search_s},
                         {"submaps_built", lc->submaps_built},
                         {"list", list}};
    std::printf("loop closure: %zu closures (%zu judged by %s, %zu false, worst %.3f m), %llu searches, %llu "
                "optimisations %.2f s, search %.2f s\n",
                closures.size(), judged, judged_by.c_str(), false_closures, worst_m,
                static_cast<unsigned long long>(lc->searches), static_cast<unsigned long long>(lc->optimizations),
                lc->optimization_s, lc->search_s);
  }
  // Baseline: the same relations scored on the reference trajectory (raw
  // odometry in a raw log, the correcting SLAM's poses in a corrected log).
  const RelationErrors ref_rel = relationErrors(scored.stamped_reference, data.relations);
  r["reference_rel_trans_err_m"] = statsJson(ref_rel.translation_m);
  r["reference_rel_rot_err_deg"] = statsJson(ref_rel.rotation_rad, kDegPerRad);
  // Baseline: the odometry the SLAM was given, scored like its output.
  if (!data.inputs.empty() && data.inputs.front().odometry) {
    std::vector<Pose2> odometry;
    for (const Slam2dInput& in : data.inputs) odometry.push_back(in.odometry.value_or(Pose2{}) * in.scan.sensor_mount);
    const RelationErrors odo_rel = relationErrors(stamped(data.inputs, odometry), data.relations);
    const Paired odo = paired(data.inputs, odometry, data.reference);
    r["odometry_baseline"] = {
        {"rel_trans_err_m", statsJson(odo_rel.translation_m)},
        {"ate_m", absoluteTrajectoryError(odo.estimate, odo.reference).rmse},
        {"rpe_1m_m", relativePoseError(odo.estimate, odo.reference, options.rpe_distance_m).translation_m.rmse}};
    std::printf("odometry alone: ATE %.4f m, RPE %.4f m, relations %.4f m\n", r["odometry_baseline"]["ate_m"].get<double>(),
                r["odometry_baseline"]["rpe_1m_m"].get<double>(), odo_rel.translation_m.mean);
  }
  // The relations are motions between scans (laser frame); where the laser
  // is off the robot centre, the same figures between base poses show
  // whether a relation file was made for base poses instead.
  const bool mounted = std::any_of(data.inputs.begin(), data.inputs.end(), [](const Slam2dInput& in) {
    return in.scan.sensor_mount.translation().norm() > 0.0 || in.scan.sensor_mount.theta_rad != 0.0;
  });
  if (mounted && rel.relations_used > 0) {
    const RelationErrors base = relationErrors(stamped(data.inputs, run.robot_poses), data.relations);
    r["rel_base_frame"] = {{"trans_err_m", statsJson(base.translation_m)},
                           {"rot_err_deg", statsJson(base.rotation_rad, kDegPerRad)}};
  }
  if (data.simulated) {
    r["ate_vs_truth_m"] = ate.rmse;
    const ReflectivityFigures rf = reflectivityFigures(data, run.laser_poses, slam);
    r["reflectivity_rel_err_median"] = rf.rel_err_median;
    r["reflectivity_spread_raw"] = rf.spread_raw;
    r["reflectivity_spread_calibrated"] = rf.spread_calibrated;
    r["reflectivity"] = {{"rel_err_median_unscaled", rf.rel_err_median_unscaled},
                         {"scale", rf.scale},
                         {"cells_compared", rf.cells_compared},
                         {"cells_spread", rf.cells_spread},
                         {"spread_ratio", rf.spread_raw / rf.spread_calibrated}};
  }

  std::printf("scans %zu (rejected %zu, non-finite %zu, outside map %zu)\n", data.inputs.size(), run.rejected,
              run.non_finite, run.outside_map);
  std::printf("relations used %zu of %zu: trans %.4f ± %.4f m, rot %.3f ± %.3f deg\n", rel.relations_used,
              data.relations.size(), rel.translation_m.mean, rel.translation_m.std, rel.rotation_rad.mean * kDegPerRad,
              rel.rotation_rad.std * kDegPerRad);
  std::printf("  (the reference itself: trans %.4f ± %.4f m, rot %.3f ± %.3f deg)\n", ref_rel.translation_m.mean,
              ref_rel.translation_m.std, ref_rel.rotation_rad.mean * kDegPerRad, ref_rel.rotation_rad.std * kDegPerRad);
  std::printf("ATE vs %s: %.4f m; RPE over %.1f m: %.4f m (%zu pairs)\n", data.reference_kind.c_str(), ate.rmse,
              options.rpe_distance_m, rpe.translation_m.rmse, rpe.translation_m.count);
  if (data.duration_s)
    std::printf("SLAM %.3f s wall, %.3f s CPU; data %.1f s; %.0fx real time (%.0fx on CPU time)\n", run.wall_s,
                run.cpu_s, *data.duration_s, realtime, *data.duration_s / run.cpu_s);
  else
    std::printf("SLAM %.3f s wall, %.3f s CPU; no real-time factor: the log's stamps do not measure time\n",
                run.wall_s, run.cpu_s);
  if (data.simulated) {
    std::printf("ATE vs truth %.4f m; reflectivity: median rel. error %.3f (scale %.3f, %zu cells), spread raw %.3f "
                "vs calibrated %.3f\n",
                ate.rmse, r["reflectivity_rel_err_median"].get<double>(), r["reflectivity"]["scale"].get<double>(),
                r["reflectivity"]["cells_compared"].get<size_t>(), r["reflectivity_spread_raw"].get<double>(),
                r["reflectivity_spread_calibrated"].get<double>());
  }
  if (!options.poses_out.empty()) writePoses(options.poses_out, data.inputs, run.laser_poses);
  if (!options.map_image_out.empty()) writeMapImage(options.map_image_out, slam.grid(), options.map_image_max_px);
  if (!options.json_out.empty()) {
    std::ofstream out(options.json_out);
    if (!out) throw std::runtime_error("cannot write " + options.json_out);
    out << r.dump(2) << "\n";
    std::cout << "wrote " << options.json_out << std::endl;
  }
  return 0;
}

}  // namespace rmap::bench
