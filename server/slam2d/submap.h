#pragma once
/// @file submap.h
/// A submap for loop closure: consecutive keyframes of one trajectory
/// rendered rigidly in the frame of its anchor keyframe (the middle one), so
/// a match against it is a constraint between the anchor and the matched
/// scan however the graph later moves the anchor.
///
/// Matching is global-then-local: the branch-and-bound correlative matcher
/// finds the best pose over a large window on a probability raster of the
/// submap, then Gauss–Newton (matchScan) refines it on the submap's own
/// occupancy pyramid. Building costs the insertion of its keyframes and the
/// matcher's precomputation, so LoopCloser builds submaps on demand and keeps
/// a few.

#include <optional>
#include <span>
#include <vector>

#include "slam2d/correlative_matcher.h"
#include "slam2d/grid_map.h"
#include "slam2d/keyframe.h"
#include "slam2d/scan_matcher.h"

namespace rmap::slam2d {

struct SubmapMatch {
  Pose2 pose;              ///< refined robot pose in the anchor's frame
  double score = 0.0;      ///< correlative score (mean occupancy probability at the endpoints, 0..1)
  MatchResult refinement;  ///< Gauss–Newton result (Hessian, residual) at `pose`
  /// Correlative score of a rival: a pose of the ambiguity window at least
  /// ambiguity_radius_m from the match scoring ≥ score − ambiguity_margin
  /// (the first the search met); 0 when there is none.
  double rival_score = 0.0;
  Eigen::Vector2d rival_m = Eigen::Vector2d::Zero();  ///< the rival's translation (anchor frame), when there is one
  bool ambiguous() const { return rival_score > 0.0; }
};

struct SubmapMatcherOptions {
  double resolution_m = 0.05;
  int levels = 2;                 ///< occupancy pyramid levels for the refinement
  float unknown_probability = 0.1f;  ///< raster value of never-observed cells
  int raster_dilation_cells = 0;     ///< radius of the correlative raster's max filter (see maxFiltered)
  OccupancyUpdate occupancy;
  CorrelativeMatcherOptions correlative;
  ScanMatcherOptions refinement;  ///< its search fields are ignored
  /// A refinement that moves farther than this from the correlative pose (m,
  /// rad) left the basin the search found: the match is refused.
  double max_refinement_shift_m = 0.1;
  double max_refinement_shift_rad = 0.05;
  /// Degeneracy: a corridor leaves a match free along its axis, repeated
  /// structure (doors, shelves) offers several places. ±ambiguity_window_m
  /// and ±ambiguity_window_rad around the found pose are searched again
  /// without the translations within ambiguity_radius_m of it; a pose
  /// scoring within ambiguity_margin of the match (a rival) makes it
  /// ambiguous (LoopCloser then weakens the closure along the rival's
  /// direction). On raw intel the 5 closures judged false against the
  /// corrected log had rivals within 0.003–0.050, the 1,411 others 5 % within
  /// 0.05, 11 % within 0.08. The heading window is one step of the loop
  /// search: a corridor fixes the heading, and ±0.05 rad cost raw fr079 3 s
  /// more search. ambiguity_margin ≤ 0: no check.
  double ambiguity_radius_m = 0.25;
  double ambiguity_window_m = 1.0;
  double ambiguity_window_rad = 0.01;
  double ambiguity_margin = 0.06;
};

class SubmapMatcher {
 public:
  /// Renders `keyframes` at anchor⁻¹ ⊕ their pose.
  /// @throws std::invalid_argument when they observe no cell
  SubmapMatcher(std::span<const Keyframe* const> keyframes, const Pose2& anchor_pose, const SubmapMatcherOptions& options);

  /// Best pose of `points` (robot frame) within ±window_m, ±window_rad of
  /// `center` (anchor frame) with a correlative score ≥ min_score, refined;
  /// nullopt when none or when the refinement leaves the found basin; an
  /// ambiguous match is returned with rival_score set.
  std::optional<SubmapMatch> match(std::span<const Eigen::Vector2d> points, const Pose2& center, double window_m,
                                   double window_rad, double min_score) const;

 private:
  SubmapMatcherOptions options_;
  GridMap2d grid_;
  std::optional<CorrelativeMatcher> correlative_;
};

}  // namespace rmap::slam2d
