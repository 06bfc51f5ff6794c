#include "slam2d/slam2d.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace rmap::slam2d {

namespace {

/// Poses farther out than this are refused: cell indices must fit in int at any resolution ≥ 1 mm.
constexpr double kMaxCoordinate_m = 1e6;
/// Weight of the newest scan in a trajectory's running mean match residual (≈ the last 10 scans).
constexpr double kResidualRate = 0.1;

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("Slam2dOptions: " + what);
}

uint64_t cellId(const Eigen::Vector2i& c) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(c.x())) << 32) | static_cast<uint32_t>(c.y());
}
Eigen::Vector2i cellFromId(uint64_t id) {
  return {static_cast<int32_t>(static_cast<uint32_t>(id >> 32)), static_cast<int32_t>(static_cast<uint32_t>(id))};
}

/// A usable beam: endpoint in the base frame, range, raw intensity, cos incidence, reflectivity.
struct Beam {
  Eigen::Vector2d end_m;
  float range_m;
  float intensity = std::numeric_limits<float>::quiet_NaN();
  float cos_incidence = std::numeric_limits<float>::quiet_NaN();
  float reflectivity = std::numeric_limits<float>::quiet_NaN();
};

void checkPose(const Pose2& p, const char* what) {
  if (!p.isFinite() || std::abs(p.x_m) > kMaxCoordinate_m || std::abs(p.y_m) > kMaxCoordinate_m)
    throw std::invalid_argument(std::string("Slam2d::addScan: ") + what + " is not finite or beyond 1e6 m");
}

/// The slipped pose of Slam2dOptions::relock_after_large_step_m. The pick is
/// the search's alone (no Gauss–Newton iterations). Picks within the first
/// search's reach are left alone: refined without the prior, one in an
/// unpushed simulated run slid 0.09 m along a weakly held direction onto a
/// lower but wrong residual.
std::optional<MatchResult> relockAfterLargeStep(const GridMap2d& map, std::span<const MatchPoint> points,
                                                const Pose2& predicted, ScanMatcherOptions matcher,
                                                const Slam2dOptions& options) {
  matcher.search_m = options.relock_after_large_step_m;
  matcher.search_translation_weight = 0.0;
  matcher.search_rotation_weight = 0.0;
  ScanMatcherOptions pick_only = matcher;
  pick_only.coarse_iterations = pick_only.fine_iterations = 0;
  const Pose2 pick = matchScan(map, points, predicted, std::nullopt, pick_only).pose;
  if ((pick.translation() - predicted.translation()).norm() <= options.search_after_large_step_m) return std::nullopt;
  matcher.search_rad = 0.0;
  return matchScan(map, points, pick, std::nullopt, matcher);
}

}  // namespace

void Slam2dOptions::validate() const {
  require(resolution_m >= 1e-3 && resolution_m <= 10.0, "resolution_m must be in [0.001, 10]");
  require(levels >= 1 && levels <= 8, "levels must be in [1, 8]");
  require(map_update_distance_m >= 0.0 && std::isfinite(map_update_distance_m), "map_update_distance_m must be ≥ 0");
  require(map_update_angle_rad >= 0.0 && std::isfinite(map_update_angle_rad), "map_update_angle_rad must be ≥ 0");
  require(range_min_m >= 0.0f && range_max_m > range_min_m && std::isfinite(range_max_m),
          "need 0 ≤ range_min_m < range_max_m < inf");
  const auto in = [](double v, double hi) { return v >= 0.0 && v <= hi; };
  require(in(odometry_heading_kappa, 1e6) && in(max_odometry_information_theta, 1e6) &&
              in(odometry_translation_kappa, 1e6) && in(max_odometry_information_xy, 1e6),
          "odometry_*_kappa and max_odometry_information_* must be in [0, 1e6]");
  require(odometry_agreement_scans >= 5 && odometry_agreement_scans <= 10000,
          "odometry_agreement_scans must be in [5, 10000]");
  require(odometry_information_xy >= 0.0 && odometry_information_theta >= 0.0 &&
              std::isfinite(odometry_information_xy) && std::isfinite(odometry_information_theta),
          "odometry information must be finite and ≥ 0");
  require(reflectivity_weight >= 0.0 && std::isfinite(reflectivity_weight), "reflectivity_weight must be ≥ 0");
  require(in(search_without_odometry_rad, 3.2) && in(sparse_search_without_odometry_rad, 3.2) &&
              in(search_after_large_step_rad, 3.2) && in(search_without_odometry_m, 5.0) &&
              in(search_after_large_step_m, 5.0),
          "the search windows must be in [0, 3.2] rad and [0, 5] m");
  require(in(search_without_odometry_rotation_weight, 1e6) && in(search_without_odometry_translation_weight, 1e6) &&
              in(search_after_large_step_translation_weight, 1e6) && in(search_after_large_step_heading_weight, 1e6),
          "search_without_odometry_*_weight and search_after_large_step_*_weight must be in [0, 1e6]");
  require(std::isfinite(relock_residual_margin) && relock_search_rad >= 0.0 && relock_search_rad <= 3.2 &&
              relock_search_m >= 0.0 && relock_search_m <= 5.0 && relock_after_large_step_m >= 0.0 &&
              relock_after_large_step_m <= 5.0,
          "relock_residual_margin must be finite, relock_search_rad in [0, 3.2], relock_search_m and "
          "relock_after_large_step_m in [0, 5] m");
  require(search_odometry_step_m >= 0.0 && search_odometry_step_rad >= 0.0, "search odometry step thresholds must be ≥ 0");
  require(local_map_keyframes >= 0, "local_map_keyframes must be ≥ 0");
  require(sparse_scan_motion_m >= 0.0 && std::isfinite(sparse_scan_motion_m), "sparse_scan_motion_m must be ≥ 0");
  require(match_point_spacing_m >= 0.0 && std::isfinite(match_point_spacing_m), "match_point_spacing_m must be ≥ 0");
  require(occupancy.hit_log_odds > 0.0f && occupancy.miss_log_odds < 0.0f &&
              occupancy.min_log_odds < 0.0f && occupancy.max_log_odds > 0.0f,
          "occupancy: need hit > 0 > miss and min < 0 < max");
  require(occupancy.value_floor_probability >= 0.0f && occupancy.value_floor_probability < 1.0f,
          "occupancy.value_floor_probability must be in [0, 1)");
  require(matcher.coarse_iterations >= 0 && matcher.fine_iterations >= 0, "matcher iterations must be ≥ 0");
  require(matcher.damping >= 0.0 && matcher.max_step_cells > 0.0 && matcher.max_step_rad > 0.0,
          "matcher damping ≥ 0 and step bounds > 0");
  require(in(matcher.flat_information_cells, 1e4) && in(matcher.flat_ratio, 1.0),
          "matcher.flat_information_cells must be in [0, 1e4] and matcher.flat_ratio in [0, 1]");
  incidence.validate();  // else a bad option would only throw at the first scan with intensities
  loop_closure.validate();
}

Eigen::Vector3d odometryPriorInformation(const std::deque<double>& translation_disagreement_m,
                                         const std::deque<double>& heading_disagreement_rad, const Slam2dOptions& options) {
  const auto information = [&](const std::deque<double>& disagreement, double kappa, double floor, double cap) {
    if (kappa <= 0.0 || 5 * disagreement.size() < static_cast<size_t>(options.odometry_agreement_scans)) return floor;
    std::vector<double> sorted(disagreement.begin(), disagreement.end());
    const auto middle = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
    std::nth_element(sorted.begin(), middle, sorted.end());
    const double sigma = 1.4826 * *middle;  // the standard deviation of normal noise with this median |error|
    return std::max(floor, std::min(sigma > 0.0 ? kappa / (sigma * sigma) : cap, cap));
  };
  const double xy = information(translation_disagreement_m, options.odometry_translation_kappa,
                                options.odometry_information_xy, options.max_odometry_information_xy);
  return {xy, xy,
          information(heading_disagreement_rad, options.odometry_heading_kappa, options.odometry_information_theta,
                      options.max_odometry_information_theta)};
}

Slam2d::Slam2d(Slam2dOptions options)
    : options_((options.validate(), options)),
      map_(options_.resolution_m, options_.levels),
      checkpoints_(options_.loop_closure.enabled ? static_cast<size_t>(options_.loop_closure.rerender_checkpoints) : 0) {
  options_.matcher.reflectivity_weight = options_.reflectivity_weight;
  if (options_.loop_closure.enabled) {
    LoopClosureOptions loop = options_.loop_closure;
    loop.submap.resolution_m = options_.resolution_m;
    loop.submap.occupancy = options_.occupancy;
    loop.submap.refinement = options_.matcher;
    loop.submap.refinement.reflectivity_weight = 0.0;  // submaps carry no reflectivity
    loop_closer_ = std::make_unique<LoopCloser>(loop);
  }
}

void Slam2d::setCalibration(const std::string& model, IntensityCalibration calibration) {
  ScannerModel& m = models_[model];
  m.calibration = std::move(calibration);
  m.sampler.reset();
  checkpoints_.clear();  // their keyframes of this model hold no (or another) reflectivity
}

const IntensityCalibration* Slam2d::calibration(const std::string& model) const {
  const auto it = models_.find(model);
  return it != models_.end() && it->second.calibration ? &*it->second.calibration : nullptr;
}

void Slam2d::maybeSelfCalibrate(ScannerModel& model) {
  CalibrationSampler& sampler = *model.sampler;
  const bool last_chance = sampler.full() && !model.tried_full;
  if (!sampler.ready() && !last_chance) return;
  model.tried_full = sampler.full();
  try {
    IntensityCalibration calibration = selfCalibrate(sampler.observations(), options_.self_calibration_fit);
    for (const IntensityObservation& o : sampler.observations()) {
      const double rho = calibration.reflectivity(o.intensity, o.range_m, o.cos_incidence);
      if (std::isfinite(rho)) map_.addReflectivityToCell(cellFromId(o.cell_id), static_cast<float>(rho));
    }
    model.calibration = std::move(calibration);
    model.sampler.reset();
    checkpoints_.clear();  // they hold this model's keyframes without reflectivity
  } catch (const std::exception&) {
    // Not enough independent views yet (the fit says why): collect more, or stop when full.
    sampler.postpone();
    if (model.tried_full) model.sampler.reset();
  }
}

std::optional<Pose2> Slam2d::pose(const std::string& trajectory) const {
  const auto it = trajectories_.find(trajectory);
  if (it == trajectories_.end()) return std::nullopt;
  return it->second.pose;
}

Pose2 Slam2d::addScan(const std::string& trajectory, const LaserScan& scan, const std::optional<Pose2>& odometry) {
  // --- Check everything before touching any state.
  const size_t n = scan.ranges_m.size();
  if (scan.angles_rad.size() != n)
    throw std::invalid_argument("Slam2d::addScan: " + std::to_string(scan.angles_rad.size()) + " angles for " +
                                std::to_string(n) + " ranges");
  if (!scan.intensities.empty() && scan.intensities.size() != n)
    throw std::invalid_argument("Slam2d::addScan: " + std::to_string(scan.intensities.size()) +
                                " intensities for " + std::to_string(n) + " ranges");
  checkPose(scan.sensor_mount, "sensor_mount");
  if (odometry) checkPose(*odometry, "odometry");
  bool any_finite = false;
  for (size_t i = 0; i < n && !any_finite; ++i)
    any_finite = std::isfinite(scan.ranges_m[i]) && std::isfinite(scan.angles_rad[i]);
  if (!any_finite) throw std::invalid_argument("Slam2d::addScan: the scan has no finite beam");

  // --- Endpoints in the base frame.
  const float range_min = std::max(options_.range_min_m, std::isfinite(scan.range_min_m) ? scan.range_min_m : 0.0f);
  const float range_max = (scan.range_max_m > 0.0f && std::isfinite(scan.range_max_m))
                              ? std::min(options_.range_max_m, scan.range_max_m)
                              : options_.range_max_m;
  // Intensity calibration state of this scanner (not created here: state is unchanged until the end).
  const auto model_it = models_.find(scan.model);
  const IntensityCalibration* calibration =
      model_it != models_.end() && model_it->second.calibration ? &*model_it->second.calibration : nullptr;
  const bool sampling = !calibration && options_.self_calibration &&
                        (model_it == models_.end() || model_it->second.sampler.has_value());
  const bool use_intensity = !scan.intensities.empty() && (calibration || sampling);
  const std::vector<float> cos_incidence = use_intensity ? cosIncidence(scan, options_.incidence) : std::vector<float>{};

  std::vector<Beam> beams;
  beams.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const float r = scan.ranges_m[i], a = scan.angles_rad[i];
    // The scan's max range itself is the "no return" reading of many scanners.
    if (!std::isfinite(r) || !std::isfinite(a) || r < range_min || r >= range_max) continue;
    Beam& b = beams.emplace_back(Beam{scan.sensor_mount * Eigen::Vector2d(r * std::cos(a), r * std::sin(a)), r});
    if (use_intensity) {
      b.intensity = scan.intensities[i];
      b.cos_incidence = cos_incidence[i];
      if (calibration)
        b.reflectivity = static_cast<float>(calibration->reflectivity(b.intensity, r, b.cos_incidence));
    }
  }
  std::vector<MatchPoint> points;
  points.reserve(beams.size());
  const double spacing2 = options_.match_point_spacing_m * options_.match_point_spacing_m;
  for (const Beam& b : beams)
    if (points.empty() || (b.end_m - points.back().p_m).squaredNorm() >= spacing2)
      points.push_back({b.end_m, b.reflectivity});

  // --- Predict, match, update.
  const auto found = trajectories_.find(trajectory);
  const bool is_new = found == trajectories_.end();
  Trajectory track;
  if (is_new) {
    track.pose = odometry.value_or(Pose2{});
  } else {
    track = found->second;
  }
  const bool odometry_step = options_.use_odometry && odometry && track.odometry;
  Pose2 predicted = track.pose;
  if (!is_new) predicted = track.pose * (odometry_step ? between(*track.odometry, *odometry) : track.last_increment);

  Pose2 estimate = predicted;
  const GridMap2d& match_map = is_new ? map_ : matchingMap(track.index);  // a joining robot locks onto the whole map
  // A slip hypothesis is decided by the scan right after it, or dropped.
  const std::optional<Pose2> last_slip_pose = std::exchange(track.slip_pose, std::nullopt);
  if (!is_new && !points.empty() && !map_.empty()) {
    const bool sparse_before = sparse(track);  // as of the scans before this one
    std::optional<PosePrior> prior;
    if (odometry_step)
      prior = PosePrior{predicted, sparse_before ? odometryPriorInformation(track.translation_disagreement_m,
                                                                            track.heading_disagreement_rad, options_)
                                                 : Eigen::Vector3d(options_.odometry_information_xy,
                                                                   options_.odometry_information_xy,
                                                                   options_.odometry_information_theta)};
    // A sparse trajectory's prior already follows how well its odometry
    // agrees, and its steps (≈ 1 m) need the coarse levels' reach: the
    // flat-direction prior is for dense ones (on the sparse corrected logs it
    // gained nothing and cost edmonton; docs/BENCHMARKS.md §4).
    ScanMatcherOptions unsearched = options_.matcher;
    if (sparse_before) unsearched.flat_information_cells = 0.0;
    ScanMatcherOptions matcher = unsearched;
    const Pose2 step = odometry_step ? between(*track.odometry, *odometry) : Pose2{};
    const bool search = !odometry_step || step.translation().norm() > options_.search_odometry_step_m ||
                        std::abs(step.theta_rad) > options_.search_odometry_step_rad;
    if (search && odometry_step) {
      matcher.search_rad = options_.search_after_large_step_rad;
      matcher.search_m = options_.search_after_large_step_m;
      matcher.search_translation_weight = options_.search_after_large_step_translation_weight;
      matcher.search_rotation_weight = options_.search_after_large_step_heading_weight * prior->information.z();
    } else if (search) {
      // Until its scans' spacing is known, a trajectory may be a sparse one.
      const bool wide = sparse_before || !track.scan_motion_m;
      matcher.search_rad = wide ? options_.sparse_search_without_odometry_rad : options_.search_without_odometry_rad;
      matcher.search_m = options_.search_without_odometry_m;
      matcher.search_rotation_weight = options_.search_without_odometry_rotation_weight;
      matcher.search_translation_weight = options_.search_without_odometry_translation_weight;
    }
    MatchResult match = matchScan(match_map, points, predicted, prior, matcher);
    std::optional<Pose2> slip_pose;  // this scan's pose if the wheels slipped
    const bool relock_after_step = search && odometry_step && options_.relock_after_large_step_m > 0.0;
    if ((!search || relock_after_step) && options_.relock_residual_margin > 0.0 && track.match_residual &&
        match.mean_residual > *track.match_residual + options_.relock_residual_margin) {
      // A poor fit for this trajectory: Gauss–Newton may sit in a wrong basin
      // (a return to older map parts, a slip the odometry missed): search
      // around the prediction.
      std::optional<MatchResult> searched;
      if (search) {
        searched = relockAfterLargeStep(match_map, points, predicted, matcher, options_);
      } else {
        matcher.search_rad = options_.relock_search_rad;
        matcher.search_m = options_.relock_search_m;
        searched = matchScan(match_map, points, predicted, prior, matcher);
      }
      // Only a fit as good as the recent ones counts as re-locked: a search
      // that merely lowers a poor residual (new ground, a corridor) slid the
      // raw mit-csail run off the map (ATE vs its corrected subset 1.2 → 13 m).
      if (searched && searched->mean_residual < match.mean_residual &&
          searched->mean_residual <= *track.match_residual + options_.relock_residual_margin) {
        // Beyond the odometry's reach a slip and a look-alike fit alike:
        // the next scan decides.
        if (search)
          slip_pose = searched->pose;
        else
          match = *searched;
      }
    }
    if (last_slip_pose && odometry_step) {
      // The previous scan's slip, taken if this scan, predicted from it,
      // fits clearly better and as well as the recent scans.
      const Pose2 slipped = *last_slip_pose * step;
      const MatchResult after_slip =
          matchScan(match_map, points, slipped, PosePrior{slipped, prior->information}, unsearched);
      if (after_slip.mean_residual + options_.relock_residual_margin < match.mean_residual &&
          after_slip.mean_residual <= *track.match_residual + options_.relock_residual_margin)
        match = after_slip;
    }
    track.slip_pose = slip_pose;
    track.match_residual = track.match_residual
                               ? (1.0 - kResidualRate) * *track.match_residual + kResidualRate * match.mean_residual
                               : match.mean_residual;
    estimate = match.pose;
    if (odometry_step) {
      const Pose2 matched = between(track.pose, estimate);
      track.translation_disagreement_m.push_back((matched.translation() - step.translation()).norm());
      track.heading_disagreement_rad.push_back(std::abs(normalizeAngle(matched.theta_rad - step.theta_rad)));
      if (track.heading_disagreement_rad.size() > static_cast<size_t>(options_.odometry_agreement_scans)) {
        track.translation_disagreement_m.pop_front();
        track.heading_disagreement_rad.pop_front();
      }
    }
  } else if (is_new && !points.empty() && !map_.empty()) {
    // A robot joining a shared map starts where its odometry says, then locks on.
    estimate = matchScan(map_, points, predicted, std::nullopt, options_.matcher).pose;
  }
  if (!estimate.isFinite() || std::abs(estimate.x_m) > kMaxCoordinate_m || std::abs(estimate.y_m) > kMaxCoordinate_m)
    estimate = predicted;

  if (!is_new) {
    const double motion = between(track.pose, estimate).translation().norm();
    track.scan_motion_m =
        track.scan_motion_m ? (1.0 - kResidualRate) * *track.scan_motion_m + kResidualRate * motion : motion;
  }
  const bool sparse_track = sparse(track);
  const Pose2 moved = between(track.last_update_pose, estimate);
  const bool update = is_new || map_.empty() || moved.translation().norm() >= options_.map_update_distance_m ||
                      std::abs(moved.theta_rad) >= options_.map_update_angle_rad;
  if (is_new) {
    track.index = names_.size();
    names_.push_back(trajectory);
    scans_.emplace_back();
    local_maps_.emplace_back();
  }
  bool keyframe_added = false;
  if (update && !beams.empty()) {
    Keyframe kf;
    kf.trajectory = track.index;
    kf.stamp_ns = scan.stamp_ns;
    kf.pose = estimate;
    kf.sensor_mount = scan.sensor_mount;
    kf.range_max_m = range_max;
    kf.ends_robot.reserve(beams.size());
    for (const Beam& b : beams) kf.ends_robot.push_back(b.end_m.cast<float>());
    if (use_intensity) {
      kf.model = scan.model;
      for (const Beam& b : beams) {
        kf.range_m.push_back(b.range_m);
        kf.intensity.push_back(b.intensity);
        kf.cos_incidence.push_back(b.cos_incidence);
      }
    }
    const std::vector<Ray> rays = insertKeyframe(map_, kf, estimate, calibration, options_.occupancy);
    if (!calibration && sampling && use_intensity) {
      ScannerModel& model = models_[scan.model];
      if (!model.sampler) model.sampler.emplace(options_.calibration_sample);
      for (size_t i = 0; i < beams.size(); ++i)
        model.sampler->add(cellId(map_.cellOf(rays[i].end_m)), beams[i].range_m, beams[i].cos_incidence,
                           beams[i].intensity);
      maybeSelfCalibrate(model);
    }
    track.last_update_pose = estimate;
    ++version_;
    if (options_.local_map_keyframes > 0 && sparse_track)
      addToLocalMaps(kf, keyframes_.size(), calibration);
    else
      local_maps_[track.index].clear();
    if (loop_closer_) {
      const double loop_spacing2 = std::pow(options_.loop_closure.match_point_spacing_m, 2);
      for (const MatchPoint& p : points)
        if (kf.match_points.empty() || (p.p_m - kf.match_points.back()).squaredNorm() >= loop_spacing2)
          kf.match_points.push_back(p.p_m);
      rendered_.push_back(estimate);
    } else {
      // Without loop closure a keyframe only anchors its scans' poses.
      kf.ends_robot = {};
      kf.range_m = kf.intensity = kf.cos_incidence = {};
    }
    track.keyframe = keyframes_.size();
    keyframes_.push_back(std::move(kf));
    checkpoints_.offer(keyframes_.size(), map_);
    keyframe_added = true;
  }
  track.last_increment = is_new ? Pose2{} : between(track.pose, estimate);
  track.pose = estimate;
  // A scan without odometry breaks the chain: the next step cannot be measured from older odometry.
  track.odometry = odometry;
  scans_[track.index].push_back({scan.stamp_ns, track.keyframe,
                                 track.keyframe ? between(keyframes_[*track.keyframe].pose, estimate) : estimate});
  trajectories_[trajectory] = track;
  if (loop_closer_) loop_closer_->confirmHeld(track.index, scan.stamp_ns);

  if (keyframe_added && loop_closer_) {
    // Each trajectory's pose and last update pose ride on its newest keyframe.
    std::vector<std::pair<Pose2, Pose2>> relative(names_.size());
    for (const auto& [name, t] : trajectories_) {
      if (!t.keyframe) continue;
      const Pose2& k = keyframes_[*t.keyframe].pose;
      relative[t.index] = {between(k, t.pose), between(k, t.last_update_pose)};
    }
    if (loop_closer_->addKeyframe(keyframes_)) applyCorrection(relative);
    return trajectories_[trajectory].pose;
  }
  return estimate;
}

void Slam2d::applyCorrection(const std::vector<std::pair<Pose2, Pose2>>& relative_to_keyframe) {
  for (auto& [name, t] : trajectories_) {
    if (!t.keyframe) continue;
    const Pose2& k = keyframes_[*t.keyframe].pose;
    t.pose = k * relative_to_keyframe[t.index].first;
    t.last_update_pose = k * relative_to_keyframe[t.index].second;
  }
  // The first keyframe the graph moved beyond the shift; those before it stay where the map holds them.
  size_t moved = 0;
  for (; moved < keyframes_.size(); ++moved) {
    const Pose2 d = between(rendered_[moved], keyframes_[moved].pose);
    if (d.translation().norm() > options_.loop_closure.rerender_shift_m ||
        std::abs(d.theta_rad) > options_.loop_closure.rerender_shift_rad)
      break;
  }
  if (moved == keyframes_.size()) return;
  size_t from = 0;
  GridMap2d map(options_.resolution_m, options_.levels);
  if (const MapCheckpoints::Checkpoint* checkpoint = checkpoints_.latestUpTo(moved)) {
    from = checkpoint->keyframes;
    map = checkpoint->map;
  }
  for (size_t k = from; k < keyframes_.size(); ++k) {
    insertKeyframe(map, keyframes_[k], keyframes_[k].pose, calibrationOf(keyframes_[k]), options_.occupancy);
    rendered_[k] = keyframes_[k].pose;
    checkpoints_.offer(k + 1, map);
  }
  map_ = std::move(map);
  rerendered_keyframes_ += keyframes_.size() - from;
  for (std::deque<LocalMap>& maps : local_maps_)
    for (LocalMap& local : maps) {
      if (std::none_of(local.keyframes.begin(), local.keyframes.end(), [&](size_t k) { return k >= from; })) continue;
      local.grid = GridMap2d(options_.resolution_m, options_.levels);
      for (size_t k : local.keyframes)
        insertKeyframe(local.grid, keyframes_[k], keyframes_[k].pose, calibrationOf(keyframes_[k]), options_.occupancy);
    }
  ++version_;
  ++graph_version_;
}

const IntensityCalibration* Slam2d::calibrationOf(const Keyframe& kf) const {
  return kf.model.empty() ? nullptr : calibration(kf.model);
}

void Slam2d::addToLocalMaps(const Keyframe& kf, size_t k, const IntensityCalibration* calibration) {
  std::deque<LocalMap>& maps = local_maps_[kf.trajectory];
  if (maps.empty()) maps.push_back({GridMap2d(options_.resolution_m, options_.levels), {}});
  for (LocalMap& local : maps) {
    insertKeyframe(local.grid, kf, kf.pose, calibration, options_.occupancy);
    local.keyframes.push_back(k);
  }
  const size_t full = static_cast<size_t>(options_.local_map_keyframes);
  if (maps.front().keyframes.size() >= full && maps.size() > 1) maps.pop_front();
  if (maps.back().keyframes.size() >= std::max<size_t>(1, full / 2))
    maps.push_back({GridMap2d(options_.resolution_m, options_.levels), {}});
}

const GridMap2d& Slam2d::matchingMap(size_t index) const {
  // A local map is used once it holds half its keyframes (from then on the front one always does).
  const std::deque<LocalMap>& maps = local_maps_[index];
  const size_t half = std::max<size_t>(1, static_cast<size_t>(options_.local_map_keyframes) / 2);
  return !maps.empty() && maps.front().keyframes.size() >= half && !maps.front().grid.empty() ? maps.front().grid : map_;
}

std::vector<LoopClosure2d> Slam2d::reported(const std::vector<KeyframeClosure>& closures) const {
  std::vector<LoopClosure2d> out;
  for (const KeyframeClosure& c : closures) {
    const Keyframe& query = keyframes_[c.query];
    const Keyframe& match = keyframes_[c.match];
    std::vector<SubmapKeyframe> submap;
    for (const auto& [k, relative] : c.submap) submap.push_back({keyframes_[k].stamp_ns, relative});
    out.push_back({names_[query.trajectory], query.stamp_ns, query.pose, names_[match.trajectory], match.stamp_ns,
                   match.pose, c.score, c.relative, std::move(submap), c.ambiguous_direction});
  }
  return out;
}

void Slam2d::confirmLoopClosures() {
  if (loop_closer_) loop_closer_->confirmAll();
}

std::vector<LoopClosure2d> Slam2d::takeLoopClosures() {
  return loop_closer_ ? reported(loop_closer_->takeClosures()) : std::vector<LoopClosure2d>{};
}

std::vector<LoopClosure2d> Slam2d::takeWithdrawnLoopClosures() {
  return loop_closer_ ? reported(loop_closer_->takeWithdrawnClosures()) : std::vector<LoopClosure2d>{};
}

std::vector<StampedPose2> Slam2d::trajectory(const std::string& trajectory) const {
  std::vector<StampedPose2> out;
  const auto it = trajectories_.find(trajectory);
  if (it == trajectories_.end()) return out;
  const std::vector<ScanRecord>& scans = scans_[it->second.index];
  out.reserve(scans.size());
  for (const ScanRecord& s : scans)
    out.push_back({s.stamp_ns, s.keyframe ? keyframes_[*s.keyframe].pose * s.relative : s.relative});
  return out;
}

}  // namespace rmap::slam2d
