#pragma once
/// @file loop_closure.h
/// Geometric loop closure for the 2D SLAM (Cartographer / Karto style) on top
/// of the Hector front end.
///
/// Every keyframe (map-update scan) becomes a node of a pose graph, joined to
/// the previous keyframe of its trajectory by the front end's relative pose.
/// A loop closure joins the query keyframe to the matched submap's anchor
/// (its middle keyframe) or, for a sparse submap, to its keyframes nearest
/// the matched pose (sparse_loop_edge_keyframes).
/// Keyframes are grouped into submaps of `submap_keyframes` consecutive ones
/// per trajectory. Each new keyframe is matched against finished submaps of
/// any trajectory (closures between trajectories are the cross-robot ones),
/// except its own trajectory's most recent ones, that lie within the search
/// window of its pose: ± window_m and ± window_rad, growing with the distance
/// the trajectory travelled since its last closure (the drift it may have
/// gathered). The branch-and-bound correlative matcher searches the window,
/// Gauss–Newton refines; a match is kept when its score reaches min_score.
///
/// Verification, because one false closure bends the whole map:
///  1. score threshold and a refinement that stays in the found basin;
///  2. a closure whose correction of the current estimate is large (beyond
///     small_correction_m / _rad) needs support: a closure of another view
///     (on a dense trajectory a keyframe support_min_separation_m or more
///     along the path away) against another submap implying the same
///     correction, within support_keyframes (on a sparse trajectory also
///     within support_wait_open_fraction of the travel since its last
///     closure); unsupported ones are dropped;
///  3. an ambiguous match (another pose of the submap fits nearly as well: a
///     corridor, repeated structure; see SubmapMatcherOptions::ambiguity_*)
///     constrains the graph only weakly (ambiguous_sigma_along_m) along the
///     direction of its rival: across a corridor it holds, along it the rest
///     of the graph decides, and a match that slid along it is left off by
///     more than max_loop_error_m after optimisation (check 5); against a
///     dense submap it is dropped (ambiguous_min_score), and a scan with
///     fewer than min_match_points points does not search at all;
///  4. a closure against a sparse submap is not tied to a keyframe the rest of
///     the submap turns (or, optionally, shifts) away from where it is drawn
///     (member_check_*);
///  5. loop edges carry a Huber loss, and after each optimisation a loop edge
///     still off by more than max_loop_error_m / _rad is disabled and the
///     graph optimised again. A closure the optimisation after it kept is
///     tentative, and accepted (reported) once a later optimisation keeps it
///     too or its trajectory went on for confirm_after_s of sensor time; a
///     tentative one a later optimisation disables is never reported, an
///     accepted one is withdrawn (ClosureLedger).
/// The graph is optimised when supported closures wait and either
/// optimize_every_keyframes keyframes passed since the last optimisation or
/// one of them corrects the estimate by more than small_correction_m.
/// No I/O, no threads.

#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "graph/pose_graph_2d.h"
#include "slam2d/closure_ledger.h"
#include "slam2d/correlative_matcher.h"
#include "slam2d/keyframe.h"
#include "slam2d/pose2.h"
#include "slam2d/submap.h"

namespace rmap::slam2d {

/// All defaults are fixed across datasets.
struct LoopClosureOptions {
  bool enabled = true;
  int submap_keyframes = 30;        ///< keyframes per submap
  int exclude_recent_submaps = 2;   ///< a trajectory's newest finished submaps it is not matched against
  int search_every_keyframes = 2;   ///< every n-th keyframe of a trajectory searches
  /// Submaps tried per searching keyframe, nearest first. After a long open
  /// loop the estimate has drifted by metres and the submap that holds the
  /// place need not be among the three nearest: raw mit-killian from one start
  /// of ten found no closure over its last 5,000 scans and drew its main
  /// corridor twice (relation error 0.985 m); with 6 every start closes
  /// (0.030–0.034 m), the corrected logs' ATE and closures false by every
  /// check hold (30 starts each), and the dense logs' search costs a third
  /// more CPU (BENCHMARKS.md §4).
  int max_candidates = 6;
  /// Search window half-widths: base + growth · (m travelled since the
  /// trajectory's last closure), capped. The cap of 20 m (reached after
  /// 380 m without a closure; it was 5 m, reached after 80 m) lets loops
  /// close whose drift passed 5 m: raw mit-killian's long corridor (its map
  /// was doubled there), infinite-corridor's worst start 3.7 → 1.5 m ATE,
  /// nothing worse on any log (BENCHMARKS.md §4).
  double window_m = 1.0;
  double window_growth_m_per_m = 0.05;
  double max_window_m = 20.0;
  double window_rad = 0.3;
  double window_growth_rad_per_m = 0.003;
  double max_window_rad = 0.8;
  /// A submap is a candidate when one of its keyframes lies within window +
  /// this of the keyframe's current position.
  double candidate_distance_m = 3.0;
  /// Correlative score a closure needs (0..1). Closures judged false against
  /// the corrected logs: raw intel 10 / 5 / 4 at 0.55 / 0.58 / 0.6, raw fr079
  /// 1 / 0 / 0; at 0.6 raw mit-killian no longer closes its long corridor loop.
  double min_score = 0.58;
  /// A sparse submap — its keyframes sparse_keyframe_spacing_m or more apart
  /// along the path on average: a log whose scans are ≈ 1 m apart makes every
  /// scan a keyframe — saw each wall from few poses, one or two hits per
  /// cell, and another view's endpoints land beside them: its raster is max
  /// filtered (submap.raster_dilation_cells = sparse_raster_dilation_cells),
  /// which also raises the scores, so a closure needs sparse_min_score. Dense
  /// submaps (raw logs, keyframes ≈ 0.2 m apart) are unchanged. On the
  /// corrected logs the filter found 2–4× the closures (edmonton 0 → 16);
  /// at 0.58 it let 14 false ones through on intel, at 0.65 10 on csail.
  double sparse_keyframe_spacing_m = 0.4;
  int sparse_raster_dilation_cells = 1;
  double sparse_min_score = 0.7;
  /// A closure against a sparse submap enters the graph as edges to this
  /// many of its keyframes, those nearest the matched pose, each with 1/n of
  /// the closure's information, and is reported against the nearest (0: one
  /// edge to the anchor). A sparse submap spans 15–30 m of path rendered
  /// rigidly from the front end's poses; an edge to its anchor carries the
  /// submap's bend into the graph. From 10 starts of each corrected log, 5
  /// against the anchor: closures judged false 32 → 4, ATE medians within
  /// the starts' spread (belgioioso 0.105 → 0.091, csail 0.193 → 0.213,
  /// edmonton 0.902 → 0.932); 1 (the nearest alone) removed as many false
  /// closures but held the graph to one scan (csail 0.193 → 0.221, one start
  /// 4.7 m). On dense submaps (keyframes ≈ 0.2 m apart, bent little) the same
  /// made raw intel worse (relation error 0.016 → 0.018, 8 false closures
  /// from 5 starts against 0), so they keep the anchor.
  int sparse_loop_edge_keyframes = 5;
  /// A sparse submap can hold a stretch the front end drew off: in a turn on
  /// the spot (a few scans from one place, overlapping little) it may err by
  /// some degrees and correct itself once the robot moves on. The scan matches
  /// the submap as a whole, so its pose relative to a keyframe of that stretch
  /// carries the stretch's error. Before a closure is tied to a keyframe, the
  /// keyframe's points are matched against the submap drawn without the views
  /// from within member_check_exclusion_m of it, within ±member_check_window_m
  /// and ±member_check_window_rad; a keyframe they turn by more than
  /// member_check_max_turn_rad, or shift by more than member_check_max_shift_m,
  /// from where it is drawn is not tied to, the next nearest is (of the
  /// 2 · sparse_loop_edge_keyframes nearest; none left: no closure).
  /// member_check_exclusion_m < 0: no check.
  ///
  /// The exclusion must cover the stretch that shares the keyframe's error, or
  /// the stretch vouches for it: 1 m leaves out a turn's other scans and a
  /// stretch drawn off as a whole. But a single scan of a turn drawn off alone
  /// can fit the views beyond 1 m (the CSAIL subset's scan 84, 6° off by the
  /// log, turned 0.03 rad by them) while the scans just before and after the
  /// turn place it right. So the check runs again without the views within
  /// member_check_near_exclusion_m only (≤ 0: once), and either verdict against
  /// a keyframe rules it out.
  double member_check_exclusion_m = 1.0;
  double member_check_near_exclusion_m = 0.3;
  double member_check_window_m = 0.3;
  double member_check_window_rad = 0.2;
  double member_check_max_turn_rad = 0.05;
  /// Metres; 0 (the default): the heading alone decides. What a bound catches:
  /// a step the odometry got wrong sideways where the scan saw too little to
  /// fix it (infinite-corridor's turn at scan 135, 0.43 m) leaves the submap
  /// drawn in two parts, and a closure tied before the break carries it. Why it
  /// is off: along a corridor this match is weakest (it slid corrected intel's
  /// keyframes 0.13–0.3 m there), and at 0.2 m, from 30 starts each,
  /// infinite-corridor gained (ATE median 0.722 → 0.690 m, closures false by
  /// every check 3 → 1) but freiburg-campus lost (0.293 → 0.298 m, 2 → 4).
  double member_check_max_shift_m = 0.0;
  /// Correlative score an ambiguous match against a dense submap needs; at 1
  /// none is kept. A dense submap's rival is a slide along a corridor the
  /// match cannot fix, and a closure weakened along it (ambiguous_sigma_along_m)
  /// adds little: at 0.68, raw intel from 10 starts had 5 closures 0.30–0.55 m
  /// off by the relations, each an ambiguous match slid along its corridor.
  /// Dropping them (with support_min_separation_m) left raw intel no false
  /// closure by either judge, its relation error 0.0161 → 0.0158 m, 3 % fewer
  /// closures, mit-killian 971 → 970, still closing its corridor loops
  /// (BENCHMARKS.md §4). Sparse submaps need sparse_min_score anyway.
  double ambiguous_min_score = 1.0;
  /// Match points (match_point_spacing_m apart) a keyframe needs to search:
  /// fewer cover under 4 m of wall, too little to fix a heading against an
  /// older submap (raw intel's false closures 5–8° off came from 31–34 points;
  /// 0.6 % of its true ones had fewer than 40).
  int min_match_points = 40;
  double small_correction_m = 0.15;
  double small_correction_rad = 0.05;
  /// Keyframes an unsupported closure waits for support; on a dense
  /// trajectory also until it travelled twice support_min_separation_m (at
  /// most four times as many keyframes). Without that wait, 10 keyframes
  /// (≈ 2.5 m on a dense trajectory) left a support 1.5 m on too little
  /// time: mit-killian's long corridor stayed doubled.
  int support_keyframes = 10;
  /// On a sparse trajectory an unsupported closure also waits until its
  /// trajectory travelled this fraction of the distance it had gone without a
  /// closure when the query was made: after a long open loop most views fail
  /// to match and the next one that does may come tens of metres on
  /// (freiburg-campus, 214 m open: the two groups that agree came 27 m
  /// apart, and 10 keyframes dropped the first). 0.3 and 0.5 gave campus
  /// 0.304 and 0.300 m ATE against 0.431, 0.15 left it a start at 16.9 m;
  /// intel kept no false closure from 30 starts (BENCHMARKS.md §4).
  /// 0: support_keyframes only.
  double support_wait_open_fraction = 0.3;
  /// The most keyframes that wait lasts (≥ support_keyframes): turning on the
  /// spot makes keyframes without travel, and each waiting closure is checked
  /// against every other. Campus needs more than 40 (at 40 its median ATE
  /// went 0.304 → 0.397 m, one start lost); 100 changed no start of campus or
  /// infinite-corridor, and 300 leaves room for open loops of about 1 km
  /// with keyframes 1 m apart (BENCHMARKS.md §4).
  int sparse_support_max_keyframes = 300;
  double support_tolerance_m = 0.15;   ///< two closures agree when their corrections differ by less
  double support_tolerance_rad = 0.05;
  /// On a dense trajectory (keyframes closer than sparse_keyframe_spacing_m
  /// on average) a closure supports another only when their query keyframes
  /// lie this far apart along the path (m): scans 0.4 m apart see the same
  /// walls and repeat the same false match (raw intel: four closures 0.35 m
  /// off, from queries 0.4–0.9 m apart, supported each other). A sparse
  /// trajectory's keyframes are views of their own (there, 1.5 m cost
  /// belgioioso 0.098 → 0.123 m ATE). With the wait below, 1.5 and 2 m both
  /// left raw intel's 10 starts without a false closure by the corrected
  /// log; 2 m also by the relations, and mit-killian closed 970 loops
  /// against 919 (BENCHMARKS.md §4).
  double support_min_separation_m = 2.0;
  int optimize_every_keyframes = 20;
  /// Standard deviations of the edges: between consecutive keyframes (the
  /// front end's relative pose; its error grows with the step, so a jump
  /// after a gap in the data does not hold the graph rigid) and of a loop
  /// closure match. A step of about 1 m (the corrected logs) gets 0.07 m and
  /// 0.010 rad: the front end's heading error per such step, against the
  /// corrected logs, is 0.007–0.011 rad rms on five of them (0.01 rad/m gave
  /// 0.015 rad). From 30 starts each, 0.01 → 0.005 rad/m: belgioioso ATE
  /// median 0.101 → 0.083 m, CSAIL subset 0.141 → 0.122 and
  /// infinite-corridor 0.722 → 0.713 with closures false by every check
  /// 4 → 1 and 3 → 1, but freiburg-campus 0.293 → 0.310 and csail 0.182 →
  /// 0.191 (BENCHMARKS.md §4).
  double sequential_sigma_m = 0.02;
  double sequential_sigma_m_per_m = 0.05;
  double sequential_sigma_rad = 0.005;
  double sequential_sigma_rad_per_m = 0.005;
  double loop_sigma_m = 0.05;
  double loop_sigma_rad = 0.02;
  /// Standard deviation of an ambiguous closure along the direction of its
  /// rival (m): about the ambiguity window, where the rival may be.
  double ambiguous_sigma_along_m = 1.0;
  double max_loop_error_m = 0.3;    ///< after optimisation, loop edges further off are rejected
  double max_loop_error_rad = 0.1;
  /// Sensor time (s) a closure kept by one optimisation waits for a later one
  /// before it is reported anyway (0: reported when first kept). During a
  /// revisit the next optimisation comes within seconds and tests it against
  /// the closures found after it: on raw intel the first closure of the run,
  /// 0.6 m off, was kept alone and disabled 1 s later, with three more; and
  /// from one start two closures 1 m off were reported after 5 s and
  /// disabled before 15 s had passed. A closure the next optimisation keeps
  /// is reported then: the hold delays only closures that stay alone.
  double confirm_after_s = 15.0;
  int cached_submaps = 8;           ///< built submap matchers kept (each costs its raster and levels)
  /// Endpoints used for loop matching are at least this far apart (m): the
  /// correlative search costs per point, and 10 cm spacing keeps every wall.
  double match_point_spacing_m = 0.1;
  /// The map is rendered again from the keyframes once one of them moved this
  /// far (m) or turned this much (rad) from where it was last rendered;
  /// smaller corrections only move the poses (re-rendering costs the
  /// insertion of every keyframe).
  double rerender_shift_m = 0.025;
  double rerender_shift_rad = 0.005;
  /// Copies of the map kept along the keyframes (see MapCheckpoints): a
  /// re-rendering starts from the last one before the first keyframe that
  /// moved beyond rerender_shift_*; the keyframes before it stay where they
  /// are, as after a small correction. 0: always from the first keyframe.
  int rerender_checkpoints = 16;
  /// Correlative search: a fixed rotation step (0.5°) instead of the one that
  /// moves the farthest endpoint by a cell (0.1° at 30 m, five times the
  /// rotations); Gauss–Newton refines the rest.
  SubmapMatcherOptions submap = [] {
    SubmapMatcherOptions o;
    o.correlative.angular_step_rad = 0.0087;
    return o;
  }();  ///< resolution and occupancy are set from Slam2dOptions
  graph::PoseGraphOptions graph;

  /// @throws std::invalid_argument naming the first bad option
  void validate() const;
};

/// A keyframe of a matched submap, as the submap was built.
struct SubmapKeyframe {
  int64_t stamp_ns = 0;
  Pose2 relative;  ///< in the frame of the closure's match keyframe (LoopClosure2d::match_pose)
};

/// One accepted geometric closure.
struct LoopClosure2d {
  std::string query_trajectory;
  int64_t query_stamp_ns = 0;
  Pose2 query_pose;       ///< the new scan's robot pose (corrected) when accepted
  std::string match_trajectory;
  int64_t match_stamp_ns = 0;
  /// The older keyframe it closed on (corrected): the matched submap's anchor,
  /// or for a sparse submap its keyframe nearest the matched pose.
  Pose2 match_pose;
  double score = 0.0;     ///< correlative match score 0..1
  Pose2 relative;         ///< the matched pose of the query in match_pose's frame (its loop edge's measurement)
  /// The submap the scan was matched against (match_trajectory's keyframes,
  /// match_pose's among them): a closure can be judged against it as a whole.
  std::vector<SubmapKeyframe> match_submap;
  /// An ambiguous match (a corridor, repeated structure): the unit direction
  /// in match_pose's frame along which `relative` is known only to about
  /// ambiguous_sigma_along_m (its loop edge is weak that way); none for a
  /// match without a rival.
  std::optional<Eigen::Vector2d> ambiguous_direction{};
};

/// Counters and timing of the loop closure, for benchmarks.
struct LoopClosureStats {
  uint64_t searches = 0;       ///< correlative searches run (keyframe × candidate submap)
  uint64_t matches = 0;        ///< searches that found a verified match
  uint64_t ambiguous = 0;      ///< of the matches, those with a rival (SubmapMatcherOptions::ambiguity_*)
  uint64_t weak_ambiguous = 0; ///< ambiguous matches below ambiguous_min_score, dropped (not in matches)
  uint64_t misdrawn = 0;       ///< matches against a sparse submap whose nearest keyframes were all drawn off (member_check_*), dropped (not in matches)
  uint64_t member_checks = 0;  ///< keyframes checked (member_check_*)
  uint64_t accepted = 0;       ///< closures accepted (reported; see ClosureLedger)
  uint64_t unsupported = 0;    ///< dropped for lack of support
  uint64_t rejected_after_optimization = 0;  ///< loop edges disabled (new ones, and accepted ones: withdrawn)
  uint64_t withdrawn = 0;      ///< accepted closures a later optimisation disabled
  uint64_t unconfirmed = 0;    ///< tentative closures a later optimisation disabled (never reported)
  uint64_t optimizations = 0;
  double search_s = 0.0, optimization_s = 0.0;  ///< wall time (steady clock)
  uint64_t submaps_built = 0;
};

/// The back end: pose graph, submaps, search and verification. Keyframes are
/// owned by the caller and indexed the same as graph nodes.
class LoopCloser {
 public:
  /// @throws std::invalid_argument for bad options
  explicit LoopCloser(LoopClosureOptions options);

  /// Adds keyframes.back() (its pose the front end's estimate), searches
  /// and, when due, optimises, writing corrected poses into `keyframes`.
  /// @return true when keyframe poses moved
  bool addKeyframe(std::vector<Keyframe>& keyframes);

  /// Accepts the tentative closures of `trajectory` (Keyframe::trajectory)
  /// held for confirm_after_s by `stamp_ns`, its newest sensor time.
  void confirmHeld(size_t trajectory, int64_t stamp_ns) { stats_.accepted += ledger_.confirmHeld(trajectory, stamp_ns); }
  /// Accepts every tentative closure: the data ended.
  void confirmAll() { stats_.accepted += ledger_.confirmAll(); }

  using Closure = KeyframeClosure;
  /// Closures accepted since the last call.
  std::vector<Closure> takeClosures() { return ledger_.takeAccepted(); }
  /// Closures withdrawn since the last call (take the accepted ones first).
  std::vector<Closure> takeWithdrawnClosures() { return ledger_.takeWithdrawn(); }
  const LoopClosureStats& stats() const { return stats_; }
  const LoopClosureOptions& options() const { return options_; }

 private:
  /// Keyframes `count` of them along `travel_m` of path lie spacing_m or more apart on average.
  static bool spacedAtLeast(double travel_m, uint64_t count, double spacing_m) {
    return count > 1 && travel_m >= spacing_m * double(count - 1);
  }
  struct SubmapInfo {
    size_t trajectory = 0;
    std::vector<size_t> keyframes;
    bool finished = false;
    double first_travel_m = 0.0, last_travel_m = 0.0;  ///< the trajectory's travel at its first and last keyframe
    bool sparse(double spacing_m) const { return spacedAtLeast(last_travel_m - first_travel_m, keyframes.size(), spacing_m); }
    size_t anchor() const { return keyframes[keyframes.size() / 2]; }
  };
  struct TrajectoryState {
    std::optional<size_t> last_keyframe;
    size_t open_submap = 0;
    std::vector<size_t> finished_submaps;
    double travel_since_closure_m = 0.0;
    double travel_m = 0.0;
    uint64_t keyframes = 0;
    bool sparse(double spacing_m) const { return spacedAtLeast(travel_m, keyframes, spacing_m); }
  };
  struct Pending {
    Closure closure;
    size_t submap = 0;  ///< the matched submap (closure.match need not be its anchor)
    /// The closure's graph edges: the submap keyframe each starts from, the
    /// query's matched pose in that keyframe's frame and the edge's information.
    struct Tie {
      size_t keyframe = 0;
      Pose2 relative;
      Eigen::Matrix3d information;
    };
    std::vector<Tie> ties;
    uint64_t added_at = 0;  ///< keyframe count when found
    double query_travel_m = 0.0;  ///< its trajectory's travel at the query keyframe
    double open_travel_m = 0.0;   ///< its trajectory's travel since its last closure, at the query keyframe
    bool supported = false;
  };

  void search(std::vector<Keyframe>& keyframes, size_t query, TrajectoryState& trajectory);
  /// The edges of a match (its pose in the anchor's frame) against a submap
  /// whose `members` are given in the anchor's frame: to the `count` members
  /// nearest the matched pose, nearest first, sharing `information` (anchor
  /// frame); count 0: one edge from the anchor.
  /// Members `drawn_right` refuses (index into members) are passed over; of
  /// the 2 · count nearest, none left: no tie.
  static std::vector<Pending::Tie> tiesOf(const SubmapMatch& match, const std::vector<std::pair<size_t, Pose2>>& members,
                                          size_t anchor, int count, const Eigen::Matrix3d& information,
                                          const std::function<bool(size_t)>& drawn_right);
  /// Whether member `index` of `submap` sits where the submap's views from
  /// elsewhere place it (member_check_*).
  bool drawnRight(const std::vector<Keyframe>& keyframes, size_t submap, size_t index);
  /// Whether `member`'s points fit where it is drawn against its submap's
  /// views beyond exclusion_m of it (true when they draw nothing or fit nowhere).
  bool fitsViewsBeyond(const std::vector<Keyframe>& keyframes, const SubmapInfo& info, const Keyframe& member,
                       double exclusion_m);
  const SubmapMatcher& matcher(const std::vector<Keyframe>& keyframes, size_t submap);
  /// The map-frame motion that moves the query keyframe where the closure says it is.
  Pose2 correction(const Pending& pending) const;
  bool agree(const Pending& a, const Pending& b) const;
  /// Whether a closure without support still waits for it (support_keyframes;
  /// on a dense trajectory also until a view support_min_separation_m on could
  /// come, on a sparse one support_wait_open_fraction of its open travel).
  bool awaitsSupport(const Pending& p, const std::vector<Keyframe>& keyframes) const;
  /// Whether two closures are independent enough to support each other: other
  /// queries, other submaps and, on a dense trajectory, support_min_separation_m apart.
  bool independentViews(const Pending& a, const Pending& b, const std::vector<Keyframe>& keyframes) const;
  bool small(const Pose2& correction, const Pose2& at) const;
  bool optimize(std::vector<Keyframe>& keyframes);
  Pose2 graphPose(size_t node) const;

  LoopClosureOptions options_;
  graph::PoseGraph2d graph_;
  std::vector<SubmapInfo> submaps_;
  std::vector<TrajectoryState> trajectories_;
  /// A built submap matcher and its keyframes' poses relative to the anchor when built.
  struct CachedSubmap {
    size_t submap = 0;
    std::vector<Pose2> relative;
    std::unique_ptr<SubmapMatcher> matcher;
  };
  /// After an optimisation: drops cached submaps the graph bent (a keyframe
  /// moved beyond rerender_shift_* relative to its anchor), so they are built again.
  void dropBentSubmaps(const std::vector<Keyframe>& keyframes);
  std::list<CachedSubmap> cache_;  ///< most recently used first
  /// drawnRight's verdicts by keyframe, with the keyframe's pose relative to
  /// its submap's anchor then: kept while it stays there (rerender_shift_*).
  struct DrawnVerdict {
    bool right = true;
    Pose2 in_anchor;
  };
  std::unordered_map<size_t, DrawnVerdict> drawn_right_;
  std::vector<Pending> pending_;
  std::vector<std::vector<size_t>> loop_edges_;  ///< each closure's edges (Pending::ties)
  ClosureLedger ledger_;
  bool awaiting_ = false;  ///< closures entered the graph since the last optimisation
  uint64_t keyframe_count_ = 0;
  uint64_t last_optimization_ = 0;
  LoopClosureStats stats_;
};

}  // namespace rmap::slam2d
