#include "slam2d/loop_closure.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace rmap::slam2d {

namespace {

void requireLoopOption(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("LoopClosureOptions: " + what);
}

bool positive(double v) { return v > 0.0 && std::isfinite(v); }
bool nonNegative(double v) { return v >= 0.0 && std::isfinite(v); }

Eigen::Matrix3d diagonalInformation(double sigma_m, double sigma_rad) {
  return Eigen::Vector3d(1.0 / (sigma_m * sigma_m), 1.0 / (sigma_m * sigma_m), 1.0 / (sigma_rad * sigma_rad))
      .asDiagonal();
}

graph::Pose2d toGraph(const Pose2& p) { return {p.x_m, p.y_m, p.theta_rad}; }

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

void LoopClosureOptions::validate() const {
  requireLoopOption(submap_keyframes >= 2, "submap_keyframes must be ≥ 2");
  requireLoopOption(exclude_recent_submaps >= 0, "exclude_recent_submaps must be ≥ 0");
  requireLoopOption(search_every_keyframes >= 1, "search_every_keyframes must be ≥ 1");
  requireLoopOption(max_candidates >= 1, "max_candidates must be ≥ 1");
  requireLoopOption(nonNegative(window_m) && nonNegative(window_growth_m_per_m) && max_window_m >= window_m &&
                        max_window_m <= 50.0,
                    "need 0 ≤ window_m ≤ max_window_m ≤ 50 and a growth ≥ 0");
  requireLoopOption(nonNegative(window_rad) && nonNegative(window_growth_rad_per_m) && max_window_rad >= window_rad &&
                        max_window_rad <= 3.14159,
                    "need 0 ≤ window_rad ≤ max_window_rad ≤ π and a growth ≥ 0");
  requireLoopOption(nonNegative(candidate_distance_m), "candidate_distance_m must be ≥ 0");
  requireLoopOption(min_score > 0.0 && min_score <= 1.0, "min_score must be in (0, 1]");
  requireLoopOption(sparse_min_score > 0.0 && sparse_min_score <= 1.0, "sparse_min_score must be in (0, 1]");
  requireLoopOption(nonNegative(sparse_keyframe_spacing_m), "sparse_keyframe_spacing_m must be ≥ 0");
  requireLoopOption(ambiguous_min_score >= 0.0 && ambiguous_min_score <= 1.0, "ambiguous_min_score must be in [0, 1]");
  requireLoopOption(min_match_points >= 0, "min_match_points must be ≥ 0");
  requireLoopOption(sparse_loop_edge_keyframes >= 0, "sparse_loop_edge_keyframes must be ≥ 0");
  requireLoopOption(std::isfinite(member_check_exclusion_m) && std::isfinite(member_check_near_exclusion_m) &&
                        positive(member_check_window_m) && member_check_window_m <= 5.0 &&
                        nonNegative(member_check_window_rad) && member_check_window_rad <= 3.14159 &&
                        nonNegative(member_check_max_shift_m) && member_check_max_shift_m <= 5.0 &&
                        nonNegative(member_check_max_turn_rad) && member_check_max_turn_rad <= 3.14159,
                    "need finite member_check_exclusion_m and member_check_near_exclusion_m, 0 < member_check_window_m ≤ 5, "
                    "0 ≤ member_check_window_rad ≤ π, 0 ≤ member_check_max_shift_m ≤ 5, 0 ≤ member_check_max_turn_rad ≤ π");
  requireLoopOption(sparse_raster_dilation_cells >= 0 && sparse_raster_dilation_cells <= 10 && submap.raster_dilation_cells >= 0 &&
                        submap.raster_dilation_cells <= 10,
                    "raster dilation must be in [0, 10] cells");
  requireLoopOption(nonNegative(small_correction_m) && nonNegative(small_correction_rad), "small_correction_* must be ≥ 0");
  requireLoopOption(support_keyframes >= 0, "support_keyframes must be ≥ 0");
  requireLoopOption(nonNegative(support_wait_open_fraction), "support_wait_open_fraction must be ≥ 0");
  requireLoopOption(sparse_support_max_keyframes >= support_keyframes,
                    "sparse_support_max_keyframes must be ≥ support_keyframes");
  requireLoopOption(nonNegative(support_tolerance_m) && nonNegative(support_tolerance_rad), "support_tolerance_* must be ≥ 0");
  requireLoopOption(nonNegative(support_min_separation_m), "support_min_separation_m must be ≥ 0");
  requireLoopOption(optimize_every_keyframes >= 1, "optimize_every_keyframes must be ≥ 1");
  requireLoopOption(positive(sequential_sigma_m) && positive(sequential_sigma_rad) && positive(loop_sigma_m) &&
                        positive(loop_sigma_rad) && nonNegative(sequential_sigma_m_per_m) &&
                        nonNegative(sequential_sigma_rad_per_m),
                    "edge standard deviations must be finite and > 0 (their growth ≥ 0)");
  requireLoopOption(std::isfinite(ambiguous_sigma_along_m) && ambiguous_sigma_along_m >= loop_sigma_m,
                    "ambiguous_sigma_along_m must be finite and ≥ loop_sigma_m");
  requireLoopOption(positive(max_loop_error_m) && positive(max_loop_error_rad), "max_loop_error_* must be > 0");
  requireLoopOption(nonNegative(confirm_after_s) && confirm_after_s <= 3600.0, "confirm_after_s must be in [0, 3600]");
  requireLoopOption(cached_submaps >= 1, "cached_submaps must be ≥ 1");
  requireLoopOption(nonNegative(match_point_spacing_m), "match_point_spacing_m must be ≥ 0");
  requireLoopOption(nonNegative(rerender_shift_m) && nonNegative(rerender_shift_rad), "rerender_shift_* must be ≥ 0");
  requireLoopOption(rerender_checkpoints >= 0, "rerender_checkpoints must be ≥ 0");
  requireLoopOption(submap.levels >= 1 && submap.levels <= 8, "submap.levels must be in [1, 8]");
  requireLoopOption(submap.unknown_probability >= 0.0f && submap.unknown_probability <= 1.0f,
                    "submap.unknown_probability must be in [0, 1]");
  requireLoopOption(nonNegative(submap.max_refinement_shift_m) && nonNegative(submap.max_refinement_shift_rad),
                    "submap.max_refinement_shift_* must be ≥ 0");
  requireLoopOption(nonNegative(submap.ambiguity_radius_m) && nonNegative(submap.ambiguity_window_m) &&
                        submap.ambiguity_window_m <= 50.0 &&
                        submap.ambiguity_window_rad >= 0.0 && submap.ambiguity_window_rad <= 3.14159 &&
                        std::isfinite(submap.ambiguity_margin),
                    "submap.ambiguity_*: radius ≥ 0, window in [0, 50] m, window_rad in [0, π], a finite margin");
  submap.correlative.validate();
  graph.validate();
}

LoopCloser::LoopCloser(LoopClosureOptions options)
    : options_((options.validate(), options)),
      graph_(options_.graph),
      ledger_(static_cast<int64_t>(std::llround(options_.confirm_after_s * 1e9))) {}

Pose2 LoopCloser::graphPose(size_t node) const {
  const graph::Pose2d& p = graph_.pose(node);
  return {p[0], p[1], p[2]};
}

bool LoopCloser::addKeyframe(std::vector<Keyframe>& keyframes) {
  const size_t q = keyframes.size() - 1;
  const Keyframe& kf = keyframes[q];
  if (graph_.nodeCount() != q) throw std::logic_error("LoopCloser::addKeyframe: keyframes out of step with the graph");
  graph_.addNode(toGraph(kf.pose));
  if (kf.trajectory >= trajectories_.size()) trajectories_.resize(kf.trajectory + 1);
  TrajectoryState& trajectory = trajectories_[kf.trajectory];
  if (trajectory.last_keyframe) {
    const Pose2 step = between(keyframes[*trajectory.last_keyframe].pose, kf.pose);
    const double d = step.translation().norm();
    graph_.addEdge({*trajectory.last_keyframe, q, toGraph(step),
                    diagonalInformation(options_.sequential_sigma_m + options_.sequential_sigma_m_per_m * d,
                                        options_.sequential_sigma_rad + options_.sequential_sigma_rad_per_m * d),
                    false});
    trajectory.travel_since_closure_m += d;
    trajectory.travel_m += d;
  }
  if (!trajectory.last_keyframe || submaps_[trajectory.open_submap].finished) {
    submaps_.push_back({kf.trajectory, {}, false, trajectory.travel_m, trajectory.travel_m});
    trajectory.open_submap = submaps_.size() - 1;
  }
  SubmapInfo& open = submaps_[trajectory.open_submap];
  open.keyframes.push_back(q);
  open.last_travel_m = trajectory.travel_m;
  if (static_cast<int>(open.keyframes.size()) >= options_.submap_keyframes) {
    open.finished = true;
    trajectory.finished_submaps.push_back(trajectory.open_submap);
  }
  trajectory.last_keyframe = q;
  ++trajectory.keyframes;
  ++keyframe_count_;

  if (trajectory.keyframes % static_cast<uint64_t>(options_.search_every_keyframes) == 0)
    search(keyframes, q, trajectory);

  // Support: a small correction agrees with the map as it is; a large one
  // needs a second closure that implies the same correction.
  bool large_correction = false;
  for (Pending& p : pending_) {
    if (p.supported) continue;
    if (small(correction(p), graphPose(p.closure.query))) {
      p.supported = true;
      continue;
    }
    for (Pending& o : pending_) {
      if (!independentViews(p, o, keyframes) || !agree(p, o)) continue;
      p.supported = o.supported = true;
      large_correction = true;
    }
  }
  std::vector<Pending> still;
  for (Pending& p : pending_) {
    if (p.supported) {
      std::vector<size_t> edges;
      for (const Pending::Tie& tie : p.ties)
        edges.push_back(graph_.addEdge({tie.keyframe, p.closure.query, toGraph(tie.relative), tie.information, true}));
      ledger_.await(edges.front(), p.closure, keyframes[p.closure.query].trajectory);
      loop_edges_.push_back(std::move(edges));
      awaiting_ = true;
      trajectories_[keyframes[p.closure.query].trajectory].travel_since_closure_m = 0.0;
    } else if (awaitsSupport(p, keyframes)) {
      still.push_back(p);
    } else {
      ++stats_.unsupported;
    }
  }
  pending_ = std::move(still);

  if (!awaiting_) return false;
  if (!large_correction && keyframe_count_ - last_optimization_ < static_cast<uint64_t>(options_.optimize_every_keyframes))
    return false;
  return optimize(keyframes);
}

void LoopCloser::search(std::vector<Keyframe>& keyframes, size_t query, TrajectoryState& trajectory) {
  const Keyframe& kf = keyframes[query];
  if (kf.match_points.empty() || kf.match_points.size() < static_cast<size_t>(options_.min_match_points)) return;
  const double travel = trajectory.travel_since_closure_m;
  const double window_m = std::min(options_.max_window_m, options_.window_m + options_.window_growth_m_per_m * travel);
  const double window_rad =
      std::min(options_.max_window_rad, options_.window_rad + options_.window_growth_rad_per_m * travel);
  const Eigen::Vector2d position = kf.pose.translation();
  const size_t recent = std::min(trajectory.finished_submaps.size(), static_cast<size_t>(options_.exclude_recent_submaps));
  const auto excluded = [&](size_t s) {
    return std::find(trajectory.finished_submaps.end() - static_cast<std::ptrdiff_t>(recent),
                     trajectory.finished_submaps.end(), s) != trajectory.finished_submaps.end();
  };
  std::vector<std::pair<double, size_t>> candidates;
  const double reach2 = std::pow(window_m + options_.candidate_distance_m, 2);
  for (size_t s = 0; s < submaps_.size(); ++s) {
    const SubmapInfo& submap = submaps_[s];
    if (!submap.finished || (submap.trajectory == kf.trajectory && excluded(s))) continue;
    double nearest2 = reach2;
    for (size_t k : submap.keyframes) nearest2 = std::min(nearest2, (keyframes[k].pose.translation() - position).squaredNorm());
    if (nearest2 < reach2) candidates.emplace_back(nearest2, s);
  }
  std::sort(candidates.begin(), candidates.end());
  if (candidates.size() > static_cast<size_t>(options_.max_candidates)) candidates.resize(static_cast<size_t>(options_.max_candidates));

  const auto t0 = std::chrono::steady_clock::now();
  for (const auto& [distance2, s] : candidates) {
    const size_t anchor = submaps_[s].anchor();
    const Pose2 center = between(keyframes[anchor].pose, kf.pose);
    ++stats_.searches;
    const bool sparse = submaps_[s].sparse(options_.sparse_keyframe_spacing_m);
    const std::optional<SubmapMatch> m = matcher(keyframes, s).match(
        kf.match_points, center, window_m, window_rad, sparse ? options_.sparse_min_score : options_.min_score);
    if (!m) continue;
    if (m->ambiguous() && !sparse && m->score < options_.ambiguous_min_score) {
      ++stats_.weak_ambiguous;
      continue;
    }
    std::vector<std::pair<size_t, Pose2>> members;  // in the anchor's frame; matcher() left this submap first in the cache
    for (size_t i = 0; i < submaps_[s].keyframes.size(); ++i)
      members.emplace_back(submaps_[s].keyframes[i], cache_.front().relative[i]);
    Eigen::Matrix3d information = diagonalInformation(options_.loop_sigma_m, options_.loop_sigma_rad);
    std::optional<Eigen::Vector2d> along;
    if (m->ambiguous()) {
      // Along the rival's direction (anchor frame, the frame of the edge's
      // translation residual) the match is only known to the ambiguity window.
      along = (m->rival_m - m->pose.translation()).normalized();
      const double weak = std::pow(options_.loop_sigma_m / options_.ambiguous_sigma_along_m, 2);
      information.topLeftCorner<2, 2>() -= (1.0 - weak) / std::pow(options_.loop_sigma_m, 2) * *along * along->transpose();
    }
    std::vector<Pending::Tie> ties =
        tiesOf(*m, members, anchor, sparse ? options_.sparse_loop_edge_keyframes : 0, information,
               [&](size_t i) { return drawnRight(keyframes, s, i); });
    if (ties.empty()) {
      ++stats_.misdrawn;
      continue;
    }
    ++stats_.matches;
    stats_.ambiguous += m->ambiguous();
    const Pose2 tie_in_anchor = m->pose * ties.front().relative.inverse();
    for (auto& member : members) member.second = tie_in_anchor.inverse() * member.second;
    if (along) along = Eigen::Rotation2Dd(-tie_in_anchor.theta_rad) * *along;  // into the tie's frame
    pending_.push_back({{query, ties.front().keyframe, m->score, ties.front().relative, std::move(members), along}, s,
                        std::move(ties), keyframe_count_, trajectory.travel_m, travel, false});
  }
  stats_.search_s += secondsSince(t0);
}

std::vector<LoopCloser::Pending::Tie> LoopCloser::tiesOf(const SubmapMatch& match,
                                                         const std::vector<std::pair<size_t, Pose2>>& members,
                                                         size_t anchor, int count, const Eigen::Matrix3d& information,
                                                         const std::function<bool(size_t)>& drawn_right) {
  if (count <= 0) return {{anchor, match.pose, information}};
  std::vector<std::pair<double, size_t>> nearest;
  for (size_t i = 0; i < members.size(); ++i)
    nearest.emplace_back((members[i].second.translation() - match.pose.translation()).squaredNorm(), i);
  const size_t considered = std::min(members.size(), 2 * static_cast<size_t>(count));
  std::partial_sort(nearest.begin(), nearest.begin() + static_cast<std::ptrdiff_t>(considered), nearest.end());
  std::vector<size_t> chosen;
  for (size_t j = 0; j < considered && chosen.size() < static_cast<size_t>(count); ++j)
    if (drawn_right(nearest[j].second)) chosen.push_back(nearest[j].second);
  std::vector<Pending::Tie> ties;
  for (size_t i : chosen) {
    const Pose2& member = members[i].second;
    // The information is in the anchor's frame; each edge's residual is in its keyframe's.
    Eigen::Matrix3d rotate = Eigen::Matrix3d::Identity();
    rotate.topLeftCorner<2, 2>() = Eigen::Rotation2Dd(member.theta_rad).toRotationMatrix();
    ties.push_back({members[i].first, member.inverse() * match.pose,
                    rotate.transpose() * information * rotate / double(chosen.size())});
  }
  return ties;
}

bool LoopCloser::drawnRight(const std::vector<Keyframe>& keyframes, size_t submap, size_t index) {
  if (options_.member_check_exclusion_m < 0.0) return true;
  const SubmapInfo& info = submaps_[submap];
  const size_t id = info.keyframes[index];
  const Keyframe& member = keyframes[id];
  const Pose2 in_anchor = between(keyframes[info.anchor()].pose, member.pose);
  if (const auto known = drawn_right_.find(id); known != drawn_right_.end()) {
    const Pose2 moved = between(known->second.in_anchor, in_anchor);
    if (moved.translation().norm() <= options_.rerender_shift_m && std::abs(moved.theta_rad) <= options_.rerender_shift_rad)
      return known->second.right;
  }
  // A stretch drawn off as a whole needs the wide exclusion; a single scan of a turn drawn off alone, the near one.
  const double wide_m = options_.member_check_exclusion_m, near_m = options_.member_check_near_exclusion_m;
  bool right = fitsViewsBeyond(keyframes, info, member, wide_m);
  // The second check only where some view lies between the two distances: elsewhere it would repeat the first.
  const auto between_exclusions = [&](size_t k) {
    const double d = (keyframes[k].pose.translation() - member.pose.translation()).norm();
    return d > std::min(near_m, wide_m) && d <= std::max(near_m, wide_m);
  };
  if (right && near_m > 0.0 && std::any_of(info.keyframes.begin(), info.keyframes.end(), between_exclusions))
    right = fitsViewsBeyond(keyframes, info, member, near_m);
  drawn_right_[id] = {right, in_anchor};
  return right;
}

bool LoopCloser::fitsViewsBeyond(const std::vector<Keyframe>& keyframes, const SubmapInfo& info, const Keyframe& member,
                                 double exclusion_m) {
  std::vector<const Keyframe*> elsewhere;
  bool observes = false;
  for (size_t k : info.keyframes) {
    if ((keyframes[k].pose.translation() - member.pose.translation()).norm() <= exclusion_m) continue;
    elsewhere.push_back(&keyframes[k]);
    observes = observes || !keyframes[k].ends_robot.empty();
  }
  // No views from elsewhere, or no pose they fit: nothing speaks against it.
  if (!observes || member.match_points.empty()) return true;
  ++stats_.member_checks;
  SubmapMatcherOptions check = options_.submap;
  check.raster_dilation_cells = options_.sparse_raster_dilation_cells;
  check.occupancy.miss_log_odds = 0.0f;  // the match reads where beams ended; the ray walk would cost most
  check.ambiguity_margin = 0.0;
  check.correlative.fast_window_m = options_.member_check_window_m;
  check.correlative.branch_levels = 3;  // the window is a few cells
  check.resolution_m *= 2.0;  // a heading off by member_check_max_turn_rad still moves points 4 m out by 2 cells
  check.levels = 1;
  check.max_refinement_shift_m = options_.member_check_window_m;  // the window bounds the answer already
  check.max_refinement_shift_rad = options_.member_check_window_rad;
  std::optional<SubmapMatcher> views;
  try {
    views.emplace(elsewhere, member.pose, check);
  } catch (const std::invalid_argument&) {
    return true;  // every return of the other views lies beyond their range cut: they draw no cell
  }
  const std::optional<SubmapMatch> m = views->match(member.match_points, Pose2{}, options_.member_check_window_m,
                                                    options_.member_check_window_rad, options_.min_score);
  // A shift only beyond member_check_max_shift_m: along a corridor this match is weakest.
  return !m || (std::abs(m->pose.theta_rad) <= options_.member_check_max_turn_rad &&
                (options_.member_check_max_shift_m <= 0.0 || m->pose.translation().norm() <= options_.member_check_max_shift_m));
}

const SubmapMatcher& LoopCloser::matcher(const std::vector<Keyframe>& keyframes, size_t submap) {
  for (auto it = cache_.begin(); it != cache_.end(); ++it) {
    if (it->submap != submap) continue;
    cache_.splice(cache_.begin(), cache_, it);
    return *cache_.front().matcher;
  }
  const SubmapInfo& info = submaps_[submap];
  const Pose2& anchor = keyframes[info.anchor()].pose;
  std::vector<const Keyframe*> members;
  std::vector<Pose2> relative;
  for (size_t k : info.keyframes) {
    members.push_back(&keyframes[k]);
    relative.push_back(between(anchor, keyframes[k].pose));
  }
  SubmapMatcherOptions options = options_.submap;
  if (info.sparse(options_.sparse_keyframe_spacing_m)) options.raster_dilation_cells = options_.sparse_raster_dilation_cells;
  cache_.push_front({submap, std::move(relative), std::make_unique<SubmapMatcher>(members, anchor, options)});
  ++stats_.submaps_built;
  if (cache_.size() > static_cast<size_t>(options_.cached_submaps)) cache_.pop_back();
  return *cache_.front().matcher;
}

void LoopCloser::dropBentSubmaps(const std::vector<Keyframe>& keyframes) {
  cache_.remove_if([&](const CachedSubmap& c) {
    const SubmapInfo& info = submaps_[c.submap];
    const Pose2& anchor = keyframes[info.anchor()].pose;
    for (size_t i = 0; i < info.keyframes.size(); ++i) {
      const Pose2 d = between(c.relative[i], between(anchor, keyframes[info.keyframes[i]].pose));
      if (d.translation().norm() > options_.rerender_shift_m || std::abs(d.theta_rad) > options_.rerender_shift_rad)
        return true;
    }
    return false;
  });
}

Pose2 LoopCloser::correction(const Pending& p) const {
  return (graphPose(p.closure.match) * p.closure.relative) * graphPose(p.closure.query).inverse();
}

bool LoopCloser::small(const Pose2& c, const Pose2& at) const {
  return ((c * at.translation()) - at.translation()).norm() <= options_.small_correction_m &&
         std::abs(c.theta_rad) <= options_.small_correction_rad;
}

bool LoopCloser::agree(const Pending& a, const Pending& b) const {
  const Pose2 ca = correction(a), cb = correction(b);
  const Eigen::Vector2d p = graphPose(b.closure.query).translation();
  return (ca * p - cb * p).norm() <= options_.support_tolerance_m &&
         std::abs(normalizeAngle(ca.theta_rad - cb.theta_rad)) <= options_.support_tolerance_rad;
}

bool LoopCloser::independentViews(const Pending& a, const Pending& b, const std::vector<Keyframe>& keyframes) const {
  // Consecutive keyframes against one submap repeat one aliasing (seen on raw
  // fr079); on a dense trajectory so do queries a few scans apart against
  // neighbouring submaps (raw intel).
  if (a.closure.query == b.closure.query || a.submap == b.submap) return false;
  const size_t t = keyframes[a.closure.query].trajectory;
  if (t != keyframes[b.closure.query].trajectory || trajectories_[t].sparse(options_.sparse_keyframe_spacing_m)) return true;
  return std::abs(a.query_travel_m - b.query_travel_m) >= options_.support_min_separation_m;
}

bool LoopCloser::awaitsSupport(const Pending& p, const std::vector<Keyframe>& keyframes) const {
  const uint64_t waited = keyframe_count_ - p.added_at;
  if (waited <= static_cast<uint64_t>(options_.support_keyframes)) return true;
  // On a dense trajectory the supporting view lies support_min_separation_m
  // on: wait for twice that much travel (bounded: turning on the spot makes
  // keyframes without travel). On a sparse one the wait grows with the open
  // loop before the query: the longer the drift, the fewer views match.
  const TrajectoryState& t = trajectories_[keyframes[p.closure.query].trajectory];
  const double since_query_m = t.travel_m - p.query_travel_m;
  if (t.sparse(options_.sparse_keyframe_spacing_m))
    return since_query_m < options_.support_wait_open_fraction * p.open_travel_m &&
           waited <= static_cast<uint64_t>(options_.sparse_support_max_keyframes);
  return since_query_m < 2.0 * options_.support_min_separation_m &&
         waited <= 4 * static_cast<uint64_t>(options_.support_keyframes);
}

bool LoopCloser::optimize(std::vector<Keyframe>& keyframes) {
  const auto t0 = std::chrono::steady_clock::now();
  last_optimization_ = keyframe_count_;
  ++stats_.optimizations;
  bool usable = graph_.optimize().usable;
  bool rejected = false;
  for (const std::vector<size_t>& edges : loop_edges_) {
    if (!graph_.edgeEnabled(edges.front())) continue;
    // A closure tied to several keyframes is off by its edges' mean error: a
    // bent submap leaves each edge off, in different directions.
    graph::Pose2d error = graph::Pose2d::Zero();
    for (size_t e : edges) error += graph_.edgeError(e) / double(edges.size());
    if (error.head<2>().norm() > options_.max_loop_error_m || std::abs(error[2]) > options_.max_loop_error_rad) {
      for (size_t e : edges) graph_.disableEdge(e);
      ++stats_.rejected_after_optimization;
      rejected = true;
    }
  }
  if (rejected) usable = graph_.optimize().usable || usable;
  const ClosureLedger::Settled settled = ledger_.settle(
      [&](size_t e) { return graph_.edgeEnabled(e); },
      [&](size_t t) { return keyframes[*trajectories_[t].last_keyframe].stamp_ns; });
  stats_.accepted += settled.accepted;
  stats_.withdrawn += settled.withdrawn;
  stats_.unconfirmed += settled.dropped_tentative;
  awaiting_ = false;
  bool moved = false;
  for (size_t i = 0; i < keyframes.size(); ++i) {
    const Pose2 p = graphPose(i);
    const Pose2 d = between(keyframes[i].pose, p);
    moved = moved || d.translation().norm() > 1e-4 || std::abs(d.theta_rad) > 1e-5;
    keyframes[i].pose = p;
  }
  if (moved) dropBentSubmaps(keyframes);
  stats_.optimization_s += secondsSince(t0);
  return usable && moved;
}

}  // namespace rmap::slam2d
