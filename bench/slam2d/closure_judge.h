#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "datasets/slam_relations.h"
#include "slam2d/laser_scan.h"
#include "slam2d/loop_closure.h"
#include "slam2d/pose2.h"

namespace rmap::bench {

/// One set of reference laser poses that judges loop closures: a corrected
/// log of the run, or the log's own reference poses.
struct ClosureJudge {
  std::string judged_by;                                ///< where the poses come from, for the report
  std::vector<std::optional<slam2d::Pose2>> reference;  ///< per input scan; none where the reference lacks the scan
  /// Per input scan: its reference pose is contradicted (markContradictedPoses) and judges nothing.
  std::vector<bool> contradicted;

  /// A closure is false when its relative pose is off by more than this.
  static constexpr double kMaxError_m = 0.3;
  static constexpr double kMaxError_rad = 5.0 * std::numbers::pi / 180.0;
  /// A scan without a reference pose borrows the nearest one within this
  /// many scans either way, carried over by the estimated motion between the
  /// two (a few scans: centimetres).
  static constexpr size_t kMaxBorrow = 30;

  /// A relation (a checked motion between two scans) that the judge's poses
  /// of its two scans miss by more than this contradicts them.
  static constexpr double kMaxRelationError_m = 0.15;
  static constexpr double kMaxRelationError_rad = 3.0 * std::numbers::pi / 180.0;

  /// None when the pose it would borrow is contradicted.
  /// @param input  index of the scan, none for a scan that cannot be named
  /// @param laser_poses  the estimated laser pose of every input scan
  std::optional<slam2d::Pose2> referenceOf(std::optional<size_t> input,
                                           const std::vector<slam2d::Pose2>& laser_poses) const;
  /// The scan whose reference pose referenceOf(input) borrows (input itself when it has one).
  std::optional<size_t> sourceOf(std::optional<size_t> input, size_t scans) const;
};

/// Index of each stamp among `stamps_ns`, without the stamps several scans
/// share (logs whose stamps were rounded): those do not name one scan.
std::unordered_map<int64_t, size_t> uniqueStampIndex(const std::vector<int64_t>& stamps_ns);

/// The input scans as the judge sees them.
struct JudgedRun {
  std::vector<int64_t> stamps_ns;            ///< per input scan; closures name their scans by stamp
  std::vector<slam2d::Pose2> sensor_mounts;  ///< per input scan, robot → laser
  std::vector<slam2d::Pose2> laser_poses;    ///< per input scan, the final estimate
  /// Per input scan, its returns in the laser frame (m), for the scan check
  /// of a false verdict (scanFit_m); empty: no scan check.
  std::vector<std::vector<Eigen::Vector2d>> scan_points;
  /// Per input scan, the odometry's laser pose (robot odometry × sensor
  /// mount), none where the scan has no odometry; for the judge's jumps
  /// (judgeJump_m). Empty: no jump check.
  std::vector<std::optional<slam2d::Pose2>> laser_odometry;
};

/// How far a scan's ends are truncated when it is fitted to a local map (m).
constexpr double kScanFitTruncation_m = 0.3;
/// The judge's local map around a closure's match: its scans this many
/// input scans either way, placed by the judge's poses (without those as
/// near the query).
constexpr size_t kScanFitNeighbours = 15;

/// A judge's step between two scans that differs from the odometry's by more
/// than this (m) is a jump of the judge: a particle filter's correction, not
/// a motion. freiburg-campus's corrected log has 16 steps 0.5–1.2 m off the
/// odometry's, mostly sideways (at scan 238 1.00 m where the wheels moved
/// 0.01 m; BENCHMARKS.md §4); on the other corrected logs no step is more
/// than 0.49 m off.
constexpr double kMaxJudgeStepJump_m = 0.5;

/// The largest difference (m) between the judge's and the odometry's
/// translation over the steps between consecutive input scans within
/// kScanFitNeighbours of `scan`, by the judge's own poses only (none
/// borrowed); none where no step has both.
std::optional<double> judgeJump_m(const ClosureJudge& judge, const JudgedRun& run, size_t scan);

/// The returns of `scan` (finite, within its range limits and below
/// range_max_m: a return at the maximum is none) in the laser frame (m).
std::vector<Eigen::Vector2d> scanReturns(const slam2d::LaserScan& scan);

/// Mean distance (m) from each of `points` placed at `pose` to its nearest
/// point of `map`, each truncated at kScanFitTruncation_m: how well a scan
/// fits a local map at that pose (lower is better; kScanFitTruncation_m when
/// `points` or `map` is empty). Brute force: for the few closures judged false.
double scanFit_m(const std::vector<Eigen::Vector2d>& points, const slam2d::Pose2& pose,
                 const std::vector<Eigen::Vector2d>& map);

/// Marks the judge's poses that `relations` contradict (the poses referenceOf
/// borrows for both scans of a relation they miss by more than
/// kMaxRelationError_*): a corrected log can be off the relations at a scan
/// (raw intel in a fast turn, 2–4.5°: BENCHMARKS.md §4), and a closure judged
/// against that pose would be called false for the judge's error. A scan
/// whose pose would come from a marked one is not judged: borrowing from
/// farther through the estimate would put the estimate's error into the
/// verdict (1 m per scan on the corrected logs).
/// @return the number of poses marked
size_t markContradictedPoses(ClosureJudge& judge, const std::vector<datasets::SlamRelation>& relations,
                             const JudgedRun& run);

/// Judges every closure against every judge: the error of its measured
/// laser-to-laser relative pose against each judge's poses of its two scans,
/// and against the submap as a whole — the judge's anchor pose fitted to all
/// the submap's keyframes (LoopClosure2d::match_submap), since the scan was
/// matched against the submap, not the anchor's scan: a judge's bad pose of
/// the anchor alone (raw mit-csail, BENCHMARKS.md §4) then does not make the
/// closure false.
/// `withdrawn` are the closures a later optimisation dropped (they stay
/// counted: they were accepted), flagged in the list and counted apart.
/// Scans that share a stamp are not judged (the stamp does not name them).
/// Two corrections of one run can disagree (raw mit-csail, BENCHMARKS.md
/// §4), so each judge's verdict is kept; the first judge's gives the
/// headline fields.
/// @return JSON: closures, withdrawn, cross_trajectory_closures;
///         closures_judged, false_closures, false_closures_withdrawn,
///         worst_closure_error_m, false_against_submap, false_across_ambiguity
///         (false with each ambiguous closure judged across its
///         LoopClosure2d::ambiguous_direction only) and judged_by (the
///         first judge's; null without a judge); ambiguous_closures; judges
///         (each judge's counts, also closures_judged_against_submap,
///         false_against_submap and false_across_ambiguity);
///         closures_judged_by_all and false_by_all_judges (with two judges or
///         more, else null);
///         with run.scan_points, the scan check of each false verdict: the
///         query's scan fitted (scanFit_m) to the judge's local map of the
///         match (its scans kScanFitNeighbours either way, by the judge's
///         poses, none as near the query) at the closure's relative pose
///         and at the judge's. A corrected log can be off along a corridor
///         (infinite-corridor, BENCHMARKS.md §4), and a closure whose pose
///         fits the scans better than the judge's is not shown false by it.
///         false_confirmed_by_scans and
///         false_across_ambiguity_confirmed_by_scans (null without scans)
///         count the false ones whose judge's pose fits at least as well
///         (scan_fit_closure_m, scan_fit_judge_m and confirmed_by_scans in
///         the list); with run.laser_odometry, each false verdict's
///         judge_jump_m (judgeJump_m, the larger at the query and at the
///         match): near a jump the judge's poses on either side of it differ by
///         its size, and so may its relative pose of the two scans.
///         false_away_from_judge_jumps and
///         false_across_ambiguity_away_from_judge_jumps (null without
///         odometry) count the false ones with no jump above
///         kMaxJudgeStepJump_m; false_credible (null without scans or
///         odometry) the false ones that every check leaves: false with the
///         ambiguous judged across their rival, confirmed by the scans and
///         away from the judge's jumps; list (each closure with `withdrawn` and
///         `ambiguous`, the first judge's errors — error_across_ambiguity_m
///         and false_across_ambiguity for an ambiguous one, submap_error_m, submap_error_deg and
///         false_against_submap where the submap had 3 keyframes with a
///         judge's pose — and, with two judges or more, by_judge);
///         with `relations`, each judge judges without the poses they
///         contradict (markContradictedPoses): judge_poses_contradicted, the
///         first judge's, and each judge's in judges; and the relations judge
///         too, chained from the match to the query (RelationChain), with the
///         same bounds: closures_judged_by_relations, false_by_relations (null
///         when no relation names two scans of the run),
///         worst_error_by_relations_m, and by_relations in the list (error_m,
///         error_deg, false, relations chained, bridge_scans, bridge_m); with
///         run.scan_points, the scan check of each false verdict by the
///         relations, the match's local map drawn by the estimate (the
///         relations hold no poses of its neighbours): scan_fit_closure_m,
///         scan_fit_relations_m and confirmed_by_scans in by_relations, and
///         false_by_relations_confirmed_by_scans (null without relations or
///         scans) counting the false ones whose chained motion fits at
///         least as well
nlohmann::json judgeClosures(const std::vector<slam2d::LoopClosure2d>& closures,
                             const std::vector<slam2d::LoopClosure2d>& withdrawn, const JudgedRun& run,
                             std::vector<ClosureJudge> judges,
                             const std::vector<datasets::SlamRelation>& relations = {});

/// Where two judges disagree: over the scans both hold a pose of (none
/// borrowed), `other` is brought onto `first` by one planar rigid motion
/// (the median heading difference, then the mean offset), and each scan's
/// heading and position differences are left. The estimate, brought onto
/// each judge the same way, shows which of the two a scan's pose agrees with.
/// @param worst  scans listed, largest heading difference first
/// @return JSON: common_scans, heading_diff_deg {median, max} (absolute),
///         scans_within_3deg, worst [{stamp_ns, heading_diff_deg,
///         position_diff_m, estimate_vs_first_deg, estimate_vs_other_deg}]
nlohmann::json judgesAgreement(const JudgedRun& run, const ClosureJudge& first, const ClosureJudge& other,
                               size_t worst = 3);

}  // namespace rmap::bench
