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
#include <random>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <unordered_map>

#include "common/machine.h"
#include "slam2d/closure_judge.h"
#include "slam2d/reflectivity_metrics.h"
#include "slam2d/revisit_consistency.h"
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
          {"reflectivity_weight", o.reflectivity_weight},
          {"value_floor_probability", o.occupancy.value_floor_probability}};
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
double orNan(const json& v) { return v.is_number() ? v.get<double>() : std::numeric_limits<double>::quiet_NaN(); }

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

/// The closures of a finished run: reported during it, confirmed at its end (the log ended:
/// closures still waiting for a later optimisation count too), and withdrawn.
struct RunClosures {
  std::vector<slam2d::LoopClosure2d> reported, confirmed_at_end, withdrawn;
};

RunClosures takeClosures(slam2d::Slam2d& slam) {
  RunClosures c;
  c.reported = slam.takeLoopClosures();
  slam.confirmLoopClosures();
  c.confirmed_at_end = slam.takeLoopClosures();
  c.reported.insert(c.reported.end(), c.confirmed_at_end.begin(), c.confirmed_at_end.end());
  c.withdrawn = slam.takeWithdrawnLoopClosures();
  return c;
}

JudgedRun judgedRun(const std::vector<Slam2dInput>& inputs, const std::vector<Pose2>& laser_poses) {
  JudgedRun run{{}, {}, laser_poses, {}, {}};
  bool odometry = false;
  for (const Slam2dInput& in : inputs) {
    run.stamps_ns.push_back(in.scan.stamp_ns);
    run.sensor_mounts.push_back(in.scan.sensor_mount);
    run.scan_points.push_back(scanReturns(in.scan));
    run.laser_odometry.push_back(in.odometry ? std::optional<Pose2>(*in.odometry * in.scan.sensor_mount) : std::nullopt);
    odometry = odometry || in.odometry.has_value();
  }
  if (!odometry) run.laser_odometry.clear();  // no jump check
  return run;
}

}  // namespace

std::vector<ClosureJudge> closureJudges(const Slam2dBenchOptions& options, const Slam2dDataset& data) {
  std::vector<ClosureJudge> judges;
  std::vector<int64_t> stamps_ns;
  for (const Slam2dInput& in : data.inputs) stamps_ns.push_back(in.scan.stamp_ns);
  const std::unordered_map<int64_t, size_t> input_of_stamp = uniqueStampIndex(stamps_ns);
  for (const std::string& path : options.closure_reference_paths) {
    Slam2dSourceOptions ref_source;
    // Found by ranges in the log whose stamps the run's scans carry (--stamps-from's, when given).
    ref_source.stamps_path = options.stamps_path.empty() ? options.source : options.stamps_path;
    ref_source.odometry = OdometrySource::kNone;
    const Slam2dDataset ref = loadSlam2dDataset(path, ref_source);
    ClosureJudge judge{"poses of " + path + " (" + std::to_string(ref.stamps_replaced) + " scans found)",
                       std::vector<std::optional<Pose2>>(data.inputs.size()), {}};
    for (size_t k = 0; k < ref.inputs.size(); ++k) {
      const auto it = input_of_stamp.find(ref.inputs[k].scan.stamp_ns);
      if (it != input_of_stamp.end() && ref.reference[k]) judge.reference[it->second] = ref.reference[k];
    }
    judges.push_back(std::move(judge));
  }
  if (judges.empty() && data.reference_kind.find("raw odometry") == std::string::npos)
    judges.push_back({data.reference_kind, data.reference, {}});
  return judges;
}

namespace {

/// The same run started elsewhere: every odometry pose moved by the rigid motion `start` (the
/// odometry's steps are unchanged), or, in a run without odometry, the first scan placed at
/// `start`. Only where the map's grid lies under the run changes, which on its own sends some
/// logs' runs elsewhere (BENCHMARKS.md §4).
/// @throws std::invalid_argument for a run whose first scan has no odometry but later ones do
std::vector<Slam2dInput> startedAt(const std::vector<Slam2dInput>& inputs, const Pose2& start) {
  std::vector<Slam2dInput> out = inputs;
  if (out.empty()) return out;
  const bool any_odometry = std::any_of(out.begin(), out.end(), [](const Slam2dInput& in) { return in.odometry; });
  if (!any_odometry) {
    out.front().odometry = start;  // a new trajectory starts at its first odometry pose
    return out;
  }
  if (!out.front().odometry)
    throw std::invalid_argument("the first scan has no odometry but later ones do: the run cannot be moved (--repeat, --start)");
  for (Slam2dInput& in : out)
    if (in.odometry) in.odometry = start * *in.odometry;
  return out;
}

/// Revisit consistency (revisit_consistency.h) of the run's sensor poses on the revisits they
/// show and, when the reference has a pose for every scan, of both on the revisits either shows.
/// @param revisits_out  empty, or a file for each revisit (Slam2dBenchOptions::revisits_out)
/// @return JSON: pairs, residual_m (null without revisits), against_reference (null without a
/// whole reference): {pairs, residual_m, reference_residual_m, lowest_estimate, lowest_reference}
json revisitJson(const std::vector<Slam2dInput>& inputs, const std::vector<slam2d::LaserScan>& scans,
                 const std::vector<Pose2>& laser_poses, const std::vector<std::optional<Pose2>>& reference,
                 const std::string& revisits_out = "") {
  const auto number = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  const RevisitConsistency own = revisitConsistency(scans, {laser_poses});
  json out = {{"pairs", own.pairs}, {"residual_m", number(own.residual_m[0])}, {"against_reference", nullptr}};
  const RevisitConsistency* listed = &own;
  RevisitConsistency both;
  if (!reference.empty() &&
      std::all_of(reference.begin(), reference.end(), [](const std::optional<Pose2>& p) { return p.has_value(); })) {
    std::vector<Pose2> ref;
    for (const std::optional<Pose2>& p : reference) ref.push_back(*p);
    both = revisitConsistency(scans, {laser_poses, ref});
    listed = &both;
    out["against_reference"] = {{"pairs", both.pairs},
                                {"residual_m", number(both.residual_m[0])},
                                {"reference_residual_m", number(both.residual_m[1])},
                                {"lowest_estimate", both.lowest[0]},
                                {"lowest_reference", both.lowest[1]}};
  }
  if (!revisits_out.empty()) {
    std::ofstream file(revisits_out);
    if (!file) throw std::runtime_error("cannot write " + revisits_out);
    // Scan indices beside the stamps: some logs carry no stamps.
    file << "# earlier_stamp_s later_stamp_s earlier_scan later_scan points run_residual_m"
         << (listed == &both ? " reference_residual_m" : "") << "\n";
    char line[200];
    for (const RevisitConsistency::Revisit& r : listed->revisits) {
      int n = std::snprintf(line, sizeof line, "%.6f %.6f %zu %zu %zu", double(inputs[r.earlier].scan.stamp_ns) * 1e-9,
                            double(inputs[r.later].scan.stamp_ns) * 1e-9, r.earlier, r.later, r.points);
      for (double residual : r.residual_m) n += std::snprintf(line + n, sizeof line - size_t(n), " %.4f", residual);
      file << line << "\n";
    }
  }
  return out;
}

/// The closure counts each run of --repeat reports (keys of judgeClosures' JSON).
constexpr const char* kRunClosureKeys[] = {"closures", "closures_judged", "false_closures", "false_against_submap",
                                           "false_across_ambiguity", "ambiguous_closures", "false_by_all_judges",
                                           "closures_judged_by_relations", "false_by_relations",
                                           "false_by_relations_confirmed_by_scans",
                                           "false_confirmed_by_scans", "false_across_ambiguity_confirmed_by_scans",
                                           "false_away_from_judge_jumps",
                                           "false_across_ambiguity_away_from_judge_jumps", "false_credible"};

/// Runs 2..n of --repeat: the run from n − 1 other starts (seeded, so reproducible), each
/// scored as the headline run is. @return JSON: runs [{start, ate_m, rpe_1m_m, rel_trans_err_m,
/// the closure counts (kRunClosureKeys), revisit_residual_m, cpu_s}] (the first
/// is `first_run`) and the median, min and max of ATE and of the revisit residual over all n runs
json repeatedRuns(const Slam2dBenchOptions& options, const Slam2dDataset& data, const std::vector<slam2d::LaserScan>& scans,
                  const std::vector<ClosureJudge>& judges, const json& first_run) {
  json runs = json::array({first_run});
  std::mt19937_64 random(1);
  std::uniform_real_distribution<double> offset_m(0.0, 1.0), heading_rad(-std::numbers::pi, std::numbers::pi);
  for (int k = 1; k < options.repeat; ++k) {
    const Pose2 start{offset_m(random), offset_m(random), heading_rad(random)};
    const std::vector<Slam2dInput> inputs = startedAt(data.inputs, start);
    slam2d::Slam2d slam(options.slam);
    const SlamRun run = runSlam(slam, inputs);
    const RunClosures closures = takeClosures(slam);
    const Paired scored = paired(inputs, run.laser_poses, data.reference);
    json one = {{"start", {start.x_m, start.y_m, start.theta_rad}},
                {"ate_m", absoluteTrajectoryError(scored.estimate, scored.reference).rmse},
                {"rpe_1m_m", relativePoseError(scored.estimate, scored.reference, options.rpe_distance_m).translation_m.rmse},
                {"rel_trans_err_m", relationErrors(stamped(inputs, run.laser_poses), data.relations).translation_m.mean},
                {"revisit_residual_m", revisitJson(inputs, scans, run.laser_poses, {})["residual_m"]},
                {"cpu_s", run.cpu_s}};
    if (slam.loopClosureStats()) {
      const json judged = judgeClosures(closures.reported, closures.withdrawn, judgedRun(inputs, run.laser_poses), judges,
                                        data.relations);
      for (const char* key : kRunClosureKeys) one[key] = judged[key];
    }
    // Printed in full: a start rounded to a few digits is another run (these runs are chaotic).
    std::printf("run %d of %d (--start %.17g %.17g %.17g): ATE %.4f m, revisit residual %.4f m", k + 1, options.repeat,
                start.x_m, start.y_m, start.theta_rad, one["ate_m"].get<double>(), orNan(one["revisit_residual_m"]));
    if (one.contains("closures")) {
      if (one["false_closures"].is_null())
        std::printf(", %zu closures (not judged)", one["closures"].get<size_t>());
      else
        std::printf(", %zu closures (%zu judged: %zu false, %zu against the whole submap%s)",
                    one["closures"].get<size_t>(), one["closures_judged"].get<size_t>(),
                    one["false_closures"].get<size_t>(), one["false_against_submap"].get<size_t>(),
                    one["false_by_all_judges"].is_null()
                        ? ""
                        : (", " + std::to_string(one["false_by_all_judges"].get<size_t>()) + " by every judge").c_str());
      if (!one["false_by_relations"].is_null())
        std::printf("; by the relations %zu of %zu false", one["false_by_relations"].get<size_t>(),
                    one["closures_judged_by_relations"].get<size_t>());
      if (!one["false_by_relations_confirmed_by_scans"].is_null())
        std::printf(" (the scans confirm %zu)", one["false_by_relations_confirmed_by_scans"].get<size_t>());
      if (!one["false_confirmed_by_scans"].is_null())
        std::printf("; the scans confirm %zu false (%zu with the ambiguous judged across their rival)",
                    one["false_confirmed_by_scans"].get<size_t>(),
                    one["false_across_ambiguity_confirmed_by_scans"].get<size_t>());
      if (!one["false_away_from_judge_jumps"].is_null())
        std::printf("; %zu false away from the judge's jumps (%zu across)", one["false_away_from_judge_jumps"].get<size_t>(),
                    one["false_across_ambiguity_away_from_judge_jumps"].get<size_t>());
      if (!one["false_credible"].is_null())
        std::printf("; %zu false by every check", one["false_credible"].get<size_t>());
    }
    std::printf(", %.1f s CPU\n", run.cpu_s);
    runs.push_back(std::move(one));
  }
  json out = {{"runs", runs}};
  // Median, min and max of one figure over the runs, into out as KEY_median, KEY_min, KEY_max.
  const auto spread = [&](const char* key, const char* what) {
    std::vector<double> v;
    for (const json& r : runs)
      if (r[key].is_number()) v.push_back(r[key].get<double>());  // null: the figure was undefined (no revisits)
    if (v.empty()) return;
    std::sort(v.begin(), v.end());
    const double median = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
    out[std::string(key) + "_median"] = median;
    out[std::string(key) + "_min"] = v.front();
    out[std::string(key) + "_max"] = v.back();
    std::printf("%s over %zu starts: median %.4f m, min %.4f, max %.4f\n", what, v.size(), median, v.front(), v.back());
  };
  spread("ate_m", "ATE");
  spread("revisit_residual_m", "revisit residual");
  if (!data.relations.empty()) spread("rel_trans_err_m", "relation error (mean)");
  return out;
}

}  // namespace

int runSlam2dBench(const Slam2dBenchOptions& options) {
  std::cout << "loading " << options.source << " ..." << std::endl;
  Slam2dSourceOptions source;
  source.relations_path = options.relations_path;
  source.reference_path = options.reference_path;
  source.stamps_path = options.stamps_path;
  source.relations_scan_period_s = options.relations_scan_period_s;
  source.relations_first_scan = options.relations_first_scan;
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
  Pose2 start;
  if (!options.start.empty()) {
    if (options.start.size() != 3) throw std::invalid_argument("--start needs x_m y_m theta_rad");
    // Runs 2..n of --repeat are moves of the logged run; one run of them is reproduced alone.
    if (options.repeat > 1) throw std::invalid_argument("--start reproduces one run: not with --repeat");
    start = {options.start[0], options.start[1], options.start[2]};
    data.inputs = startedAt(data.inputs, start);
  }
  if (options.repeat > 1) startedAt(data.inputs, start);  // refuses a run it cannot move before the first run
  std::cout << data.name << ": " << data.inputs.size() << " scans, odometry: " << data.odometry_kind
            << ", reference: " << data.reference_kind
            << (data.scans_numbered ? "; its stamps do not tell the scans apart: numbered instead" : "") << std::endl;

  slam2d::Slam2d slam(options.slam);
  const SlamRun run = runSlam(slam, data.inputs);
  const RunClosures run_closures = takeClosures(slam);
  const std::vector<slam2d::LoopClosure2d>& closures = run_closures.reported;
  const std::vector<slam2d::LoopClosure2d>& confirmed_at_end = run_closures.confirmed_at_end;

  const RelationErrors rel = relationErrors(stamped(data.inputs, run.laser_poses), data.relations);
  const Paired scored = paired(data.inputs, run.laser_poses, data.reference);
  const ErrorStats ate = absoluteTrajectoryError(scored.estimate, scored.reference);
  const RelativePoseErrors rpe = relativePoseError(scored.estimate, scored.reference, options.rpe_distance_m);
  std::vector<slam2d::LaserScan> scans;
  for (const Slam2dInput& in : data.inputs) scans.push_back(in.scan);
  const json revisits = revisitJson(data.inputs, scans, run.laser_poses, data.reference, options.revisits_out);
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
            {"scans_numbered", data.scans_numbered},
            {"relations_file", options.relations_path},
            {"relations_total", data.relations.size() + data.relations_dropped},
            {"relations_placed_by_scan_period",
             options.relations_scan_period_s > 0.0
                 ? json{{"period_s", options.relations_scan_period_s}, {"first_scan", options.relations_first_scan},
                        {"dropped", data.relations_dropped}}
                 : json(nullptr)},
            {"relations_used", rel.relations_used},
            {"rel_trans_err_m", statsJson(rel.translation_m)},
            {"rel_rot_err_deg", statsJson(rel.rotation_rad, kDegPerRad)},
            {"ate_vs_reference_m", ate.rmse},
            {"rpe_1m_m", rpe.translation_m.rmse},
            {"rpe", {{"distance_m", options.rpe_distance_m},
                     {"pairs", rpe.translation_m.count},
                     {"trans_m", statsJson(rpe.translation_m)},
                     {"rot_deg", statsJson(rpe.rotation_rad, kDegPerRad)}}},
            {"revisit_consistency", revisits},
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
  const std::vector<ClosureJudge> judges =
      slam.loopClosureStats() ? closureJudges(options, data) : std::vector<ClosureJudge>{};
  if (const slam2d::LoopClosureStats* lc = slam.loopClosureStats()) {
    const JudgedRun judged_run = judgedRun(data.inputs, run.laser_poses);
    json lc_json = judgeClosures(closures, run_closures.withdrawn, judged_run, judges, data.relations);
    if (judges.empty()) lc_json["judged_by"] = "none (raw odometry is no reference)";
    lc_json.update({{"keyframes", slam.keyframeCount()},
                    {"searches", lc->searches},
                    {"matches", lc->matches},
                    {"ambiguous", lc->ambiguous},
                    {"weak_ambiguous", lc->weak_ambiguous},
                    {"misdrawn", lc->misdrawn},
                    {"member_checks", lc->member_checks},
                    {"accepted", lc->accepted},
                    {"unsupported", lc->unsupported},
                    {"rejected_after_optimization", lc->rejected_after_optimization},
                    {"withdrawn_by_the_graph", lc->withdrawn},
                    {"unconfirmed", lc->unconfirmed},
                    {"confirmed_at_end", confirmed_at_end.size()},
                    {"optimizations", lc->optimizations},
                    {"graph_versions", slam.graphVersion()},
                    {"rerendered_keyframes", slam.rerenderedKeyframes()},
                    {"optimization_s", lc->optimization_s},
                    {"search_s", lc->search_s},
                    {"submaps_built", lc->submaps_built}});
    std::printf("loop closure: %zu closures (%zu withdrawn later, %zu confirmed at the end; %llu unconfirmed, not "
                "reported), %llu searches, %llu optimisations %.2f s, search %.2f s\n",
                closures.size(), lc_json["withdrawn"].get<size_t>(), confirmed_at_end.size(),
                static_cast<unsigned long long>(lc->unconfirmed), static_cast<unsigned long long>(lc->searches),
                static_cast<unsigned long long>(lc->optimizations), lc->optimization_s, lc->search_s);
    for (const json& j : lc_json["judges"]) {
      const std::string vetted =
          data.relations.empty() ? ""
                                 : " (" + std::to_string(j["judge_poses_contradicted"].get<size_t>()) +
                                       " of its poses contradict the relations: what they would judge is not)";
      std::printf("  %zu judged by %s%s: %zu false (%zu of them withdrawn later), worst %.3f m; against the whole "
                  "submap %zu false of %zu; %zu false with the %zu ambiguous judged across their rival only\n",
                  j["closures_judged"].get<size_t>(), j["judged_by"].get<std::string>().c_str(), vetted.c_str(),
                  j["false_closures"].get<size_t>(),
                  j["false_closures_withdrawn"].get<size_t>(),
                  j["worst_closure_error_m"].is_null() ? 0.0 : j["worst_closure_error_m"].get<double>(),
                  j["false_against_submap"].get<size_t>(), j["closures_judged_against_submap"].get<size_t>(),
                  j["false_across_ambiguity"].get<size_t>(), lc_json["ambiguous_closures"].get<size_t>());
      if (!j["false_confirmed_by_scans"].is_null())
        std::printf("    of the false, the scans fit the judge's pose at least as well as the closure's for %zu (%zu "
                    "with the ambiguous judged across their rival)\n",
                    j["false_confirmed_by_scans"].get<size_t>(),
                    j["false_across_ambiguity_confirmed_by_scans"].get<size_t>());
      if (!j["false_away_from_judge_jumps"].is_null())
        std::printf("    of the false, %zu (%zu with the ambiguous judged across their rival) lie away from the judge's "
                    "jumps (a step more than %.1f m off the odometry's within %zu scans)\n",
                    j["false_away_from_judge_jumps"].get<size_t>(),
                    j["false_across_ambiguity_away_from_judge_jumps"].get<size_t>(), kMaxJudgeStepJump_m,
                    kScanFitNeighbours);
      if (!j["false_credible"].is_null())
        std::printf("    false by every check (across the rival, confirmed by the scans, away from the jumps): %zu\n",
                    j["false_credible"].get<size_t>());
    }
    if (!lc_json["false_by_relations"].is_null()) {
      std::printf("  %zu judged by the relations chained from match to query: %zu false, worst %.3f m\n",
                  lc_json["closures_judged_by_relations"].get<size_t>(), lc_json["false_by_relations"].get<size_t>(),
                  lc_json["worst_error_by_relations_m"].is_null() ? 0.0
                                                                  : lc_json["worst_error_by_relations_m"].get<double>());
      if (!lc_json["false_by_relations_confirmed_by_scans"].is_null())
        std::printf("    of them confirmed by the scans (the query fits the match's neighbours, drawn by the "
                    "estimate, at least as well at the chained motion): %zu\n",
                    lc_json["false_by_relations_confirmed_by_scans"].get<size_t>());
    }
    if (judges.size() > 1) {
      std::printf("  false by every judge: %zu of the %zu closures all judged\n",
                  lc_json["false_by_all_judges"].get<size_t>(), lc_json["closures_judged_by_all"].get<size_t>());
      json agreement = json::array();
      for (size_t j = 1; j < judges.size(); ++j) {
        json a = judgesAgreement(judged_run, judges.front(), judges[j]);
        if (a.contains("worst")) {
          std::printf("  judge %zu against the first: %zu scans in common, %zu within 3°, the worst:", j + 1,
                      a["common_scans"].get<size_t>(), a["scans_within_3deg"].get<size_t>());
          for (const json& w : a["worst"])
            std::printf(" %.1f° at %lld (estimate %.1f° from the first, %.1f° from this one);",
                        w["heading_diff_deg"].get<double>(), static_cast<long long>(w["stamp_ns"].get<int64_t>()),
                        w["estimate_vs_first_deg"].get<double>(), w["estimate_vs_other_deg"].get<double>());
          std::printf("\n");
        }
        agreement.push_back(std::move(a));
      }
      lc_json["judges_agreement"] = std::move(agreement);  // judge 2, 3, … against the first
    }
    r["loop_closure"] = std::move(lc_json);
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
              data.relations.size() + data.relations_dropped, rel.translation_m.mean, rel.translation_m.std,
              rel.rotation_rad.mean * kDegPerRad, rel.rotation_rad.std * kDegPerRad);
  std::printf("  (the reference itself: trans %.4f ± %.4f m, rot %.3f ± %.3f deg)\n", ref_rel.translation_m.mean,
              ref_rel.translation_m.std, ref_rel.rotation_rad.mean * kDegPerRad, ref_rel.rotation_rad.std * kDegPerRad);
  std::printf("ATE vs %s: %.4f m; RPE over %.1f m: %.4f m (%zu pairs)\n", data.reference_kind.c_str(), ate.rmse,
              options.rpe_distance_m, rpe.translation_m.rmse, rpe.translation_m.count);
  std::printf("revisits: %zu scan pairs, residual %.4f m\n", revisits["pairs"].get<size_t>(), orNan(revisits["residual_m"]));
  if (const json& both = revisits["against_reference"]; !both.is_null())
    std::printf("  with the reference's: %zu pairs, residual %.4f m, the reference %.4f m (lower at %zu vs %zu pairs)\n",
                both["pairs"].get<size_t>(), orNan(both["residual_m"]), orNan(both["reference_residual_m"]),
                both["lowest_estimate"].get<size_t>(), both["lowest_reference"].get<size_t>());
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
  if (options.repeat > 1) {
    json first = {{"start", {start.x_m, start.y_m, start.theta_rad}}, {"ate_m", ate.rmse}, {"rpe_1m_m", rpe.translation_m.rmse},
                  {"rel_trans_err_m", rel.translation_m.mean}, {"revisit_residual_m", revisits["residual_m"]},
                  {"cpu_s", run.cpu_s}};
    if (r.contains("loop_closure")) {
      for (const char* key : kRunClosureKeys) first[key] = r["loop_closure"][key];
    }
    r["repeated"] = repeatedRuns(options, data, scans, judges, first);
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
