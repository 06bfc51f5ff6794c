#pragma once
/// @file slam2d.h
/// Hector-style 2D SLAM front end: one map (occupancy pyramid + reflectivity)
/// shared by any number of robot trajectories, each tracked by scan-to-map
/// matching with the odometry increment as an optional prior. No I/O, no threads.
///
/// Per scan: beams inside the range limits become endpoints in the robot
/// base frame; the prediction is the last pose ⊕ the odometry increment (or
/// the last increment again without odometry); the matcher refines it coarse
/// to fine (a correlative search first when the prediction is weak); when the
/// pose moved or turned past the thresholds since that trajectory's last map
/// update, the scan goes into every pyramid level and, for a calibrated
/// scanner model, each return's reflectivity ρ = I / g(r, α) into the finest
/// cell it ended in.
///
/// Reflectivity needs a calibration per scanner model (LaserScan::model):
/// setCalibration, or self-calibration. While a model has none, each map
/// update offers its returns (cell, range, incidence from cosIncidence, raw
/// intensity) to a CalibrationSampler, bounded in readings and views per cell;
/// once enough cells were seen from varied ranges or angles, selfCalibrate
/// runs on the sample (retried with twice the requirement after a failure,
/// once more when the sample is full, then given up); on success the sample's
/// own readings are fused into the layer and later scans are fused as they
/// come. Self-calibration fixes the scale by normalisation (median cell
/// ρ = 0.5, see self_calibration.h).

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "slam2d/calibration_sampler.h"
#include "slam2d/grid_map.h"
#include "slam2d/incidence.h"
#include "slam2d/intensity_calibration.h"
#include "slam2d/keyframe.h"
#include "slam2d/laser_scan.h"
#include "slam2d/loop_closure.h"
#include "slam2d/map_checkpoints.h"
#include "slam2d/pose2.h"
#include "slam2d/scan_matcher.h"
#include "slam2d/self_calibration.h"

namespace rmap::slam2d {

/// All defaults are fixed across datasets (tuned on real logs, checked on held-out ones).
struct Slam2dOptions {
  double resolution_m = 0.05;            ///< finest level cell edge (m)
  int levels = 3;                        ///< each level twice the cell edge of the one below
  /// The map is updated when the pose moved this far (m) or turned this much
  /// (rad) since that trajectory's last update. Fewer updates accumulate less
  /// of the matcher's noise into the map: on the raw intel log 0.2 m / 0.1 rad
  /// gave a third of the relation error of 0.05 m / 0.03 rad.
  double map_update_distance_m = 0.2;
  double map_update_angle_rad = 0.1;
  float range_min_m = 0.1f;              ///< beams outside [min, max] are ignored (and outside the scan's own limits)
  float range_max_m = 30.0f;
  bool use_odometry = true;              ///< odometry as prediction and prior when scans carry it
  /// Prior weight on the odometry prediction, per unit of the mean per-point
  /// data term (see PosePrior): x and y (1/m²), θ (1/rad²). The prediction
  /// always seeds the matcher; the prior adds a pull towards it. Wheel
  /// odometry of real robots is good in translation over one scan and biased
  /// in heading, so only translation gets a (weak) pull: on the raw intel log
  /// it stops the pose from jittering by several cm while the robot turns on
  /// the spot, which otherwise, in one run in three, broke the map when the
  /// robot came back (relation error 0.02–0.18 m over beam spacings 0.025–0.1 m
  /// without it, 0.02–0.05 m with it); any heading weight raised the error.
  double odometry_information_xy = 0.05;
  double odometry_information_theta = 0.0;
  /// Weight of the reflectivity residual in the matcher, per point relative
  /// to the occupancy residual (0 = off). Reflectivity ρ is dimensionless
  /// (≈ 0–1), the occupancy residual too, so 1 weighs them alike.
  double reflectivity_weight = 0.0;
  /// Matching uses endpoints at least this far apart (m), so dense scans cost
  /// no more than sparse ones; the map update uses every beam.
  double match_point_spacing_m = 0.05;
  /// Without an odometry step the prediction (constant velocity) can be far
  /// off: the matcher then first searches headings and translations within
  /// this much of it (ScanMatcherOptions::search_rad, search_m). A search
  /// over ±search_after_large_step_rad / _m runs when the odometry step
  /// exceeds search_odometry_step_m or _rad (sparse logs: odometry error
  /// grows with the step); scans at a few Hz stay below and cost no search.
  /// On the corrected logs (scans ≈ 1 m apart) it lowered the bench's RPE
  /// over 1 m on csail 0.163 → 0.060 m, belgioioso 0.139 → 0.057, intel
  /// 0.098 → 0.085, freiburg-101 0.067 → 0.044, edmonton 0.079 → 0.064
  /// (infinite-corridor 0.059 → 0.060; a ±0.4 m window after a step was worse).
  double search_without_odometry_rad = 0.8;
  double search_without_odometry_m = 0.4;
  double search_after_large_step_rad = 0.8;
  double search_after_large_step_m = 0.2;
  /// Without odometry a sparse trajectory (see sparse_scan_motion_m) may turn
  /// 40–60° between scans, and one that reverses its turn lands farther from
  /// the constant-velocity prediction than ±0.8 rad: its heading search spans
  /// this much instead. The wider search finds more poses that fit as well
  /// as the right one in places that look alike, so without odometry the
  /// search weighs each candidate by its distance to the prediction
  /// (ScanMatcherOptions::search_*_weight). A trajectory whose spacing is not
  /// known yet (its first scans) searches as a sparse one. On the CSAIL
  /// subset (686 scans 0.5–1 m apart, no odometry) from 10 starts with loop
  /// closure: ATE median 2.68 m (0.78–24.7) → 0.130 m (0.079–0.248); the
  /// neighbouring settings (rotation weight 0.07–0.15, translation 0.25–2,
  /// window 1.2–2.4 rad) gave 0.116–0.156 m. The weights alone (window
  /// 0.8 rad) left it lost (3.7 m); the window alone at 1.6 rad, 0.395 m with
  /// one start lost. Dense trajectories keep 0.8 rad: on raw intel without
  /// odometry the weights lowered the relation error 0.048 → 0.022 m, the
  /// same at 0.8 and 1.6 rad, which cost 2.4× the time. With odometry the
  /// weights cost corrected intel false closures (docs/BENCHMARKS.md §4).
  double sparse_search_without_odometry_rad = 1.6;
  double search_without_odometry_rotation_weight = 0.1;     ///< 1/rad²
  double search_without_odometry_translation_weight = 0.5;  ///< 1/m²
  /// The search after a large odometry step weighs each candidate's score by
  /// exp(−w·|Δt|²), Δt its shift from the odometry's prediction (m): along a
  /// corridor, or where a scan reaches past the mapped ends of walls, shifts
  /// score alike or a few per cent better for the wrong reason, and a ±0.2 m
  /// pick per scan walks the trajectory along the axis. At 2 (a 0.2 m shift
  /// costs 8 %), from 10 starts of each corrected log with loop closure, ATE
  /// medians: csail 0.210 → 0.192 m, edmonton 0.808 → 0.774,
  /// infinite-corridor 0.852 → 0.779, belgioioso 0.098 → 0.087, intel
  /// 0.080 → 0.078, freiburg-101 0.043 → 0.042 (docs/BENCHMARKS.md §4).
  double search_after_large_step_translation_weight = 2.0;  ///< 1/m²
  /// ... and by exp(−w·I_θ·Δθ²), Δθ its turn from the prediction (rad), I_θ
  /// the heading prior's information (odometryPriorInformation: high only
  /// where the odometry's headings have agreed with the matches; a fixed
  /// weight cost corrected intel false closures). Gauss–Newton cannot undo a
  /// wrong pick: the data term's curvature in θ dwarfs the prior's. Outdoors
  /// the search turned the freiburg-campus run by 8–24° onto look-alike
  /// structure at single scans its odometry got within 0.2–6°, and the run
  /// was lost. At 1 (I_θ at its cap 20: a 2° turn keeps 98 % of its score,
  /// 24° 3 %), ATE medians from 10 starts with loop closure: campus 28.6 →
  /// 0.32 m, csail 0.192 → 0.179, the other logs within their spread between
  /// starts and their revisit residuals unchanged (docs/BENCHMARKS.md §4).
  /// Dense trajectories have no heading prior, so no weight.
  double search_after_large_step_heading_weight = 1.0;
  double search_odometry_step_m = 0.3;
  double search_odometry_step_rad = 0.2;
  /// Re-locking: when a match (after a small odometry step, no search) fits
  /// worse than the trajectory's recent matches — its mean residual 1 − M
  /// above their running mean by more than relock_residual_margin (≤ 0: off)
  /// — the match is repeated with a search over ±relock_search_rad and
  /// ±relock_search_m around the prediction; the searched pose is kept when it
  /// fits better and within the margin of the recent matches. Raw fr079 over
  /// a grid of nearby settings (iterations, levels, resolution 0.04, point
  /// spacing): relation error 0.036–0.70 m without, 0.036–0.038 m with. Raw
  /// intel stays 0.02–0.11 either way (loop drift beyond any local search,
  /// see docs/BENCHMARKS.md §4).
  double relock_residual_margin = 0.02;
  double relock_search_rad = 0.2;
  double relock_search_m = 0.2;
  /// Wheel slips: after a large odometry step's search, the same test; then a
  /// search over ±relock_after_large_step_m (0: off) and
  /// ±search_after_large_step_rad without weights. Only a pick beyond the
  /// first search's reach (search_after_large_step_m) counts: the odometry
  /// slipped there, or the scan fits a look-alike. The pick is refined
  /// without the odometry's prior (which would haul it back to the
  /// prediction) and, if it fits as above, the next scan decides: it is
  /// matched from the slipped pose too, and the slip is taken if that fits
  /// better by relock_residual_margin and within it of the recent scans. A
  /// sparse run pushed 0.4 m sideways unseen by the wheels follows the push
  /// without it and is back from the next scan on with it (0.6 m). Taking the
  /// pick at once also brought campus's worst start back (1.08 → 0.36 m) but
  /// locked intel onto a look-alike (2 false closures). With the next scan
  /// deciding, from 10 starts (docs/BENCHMARKS.md §4): intel 0.069 → 0.071 m
  /// (worst 0.081 → 0.093), no false closure; infinite-corridor 0.747 →
  /// 0.677 (worst 0.906 → 1.100); campus, edmonton, csail, belgioioso,
  /// freiburg-101 the same. Off by default until more starts decide.
  double relock_after_large_step_m = 0.0;
  /// Sparse trajectories: a trajectory whose scans are on average (running
  /// mean over ≈ 10 scans) sparse_scan_motion_m or more apart — logs that
  /// keep one scan per ≈ 1 m or 0.5 rad, as the corrected logs do; raw logs
  /// move ≤ 0.1 m per scan — is matched against a local map of its own
  /// newest keyframes, between half local_map_keyframes and that many
  /// (Cartographer-style double buffering), instead of the whole map: a
  /// sparse scan overlaps the map's older, drifted parts as much as the
  /// recent ones and was pulled onto doubled walls; returns to old places are
  /// left to the loop closure. With loop closure on (and its sparse
  /// submaps), corrected intel's ATE went 0.22 → 0.09 m, belgioioso 0.16 →
  /// 0.09, but csail 0.13 → 0.23: it was held by re-locking onto old parts
  /// (docs/BENCHMARKS.md §4, *Sparse logs*; 40–70 keyframes gave alike
  /// figures, 10–30 worse). A trajectory joining a shared map locks onto the
  /// whole map first. local_map_keyframes 0: off.
  double sparse_scan_motion_m = 0.3;
  int local_map_keyframes = 70;
  /// Sparse trajectories: a heading prior that follows how well the
  /// odometry's headings agree with the matches. σ = 1.4826 · the median of
  /// |matched − odometry| heading step (rad) over the trajectory's last
  /// odometry_agreement_scans odometry steps (at least a fifth of them); the
  /// prior's θ information (as odometry_information_theta) is then
  /// odometry_heading_kappa / σ², at most max_odometry_information_theta.
  /// Wheel headings of sparse logs differ 5–15× in quality between robots
  /// (docs/BENCHMARKS.md §4): a fixed weight helped those that turn little
  /// and broke those that turn much. Corrected logs with loop closure, ATE
  /// medians over 10 starts without → with: intel 0.092 → 0.080 (false
  /// closures 3 → 0), edmonton 0.93 → 0.81, infinite-corridor 1.05 → 0.96,
  /// campus 65 → 57, csail 0.213 → 0.210, belgioioso 0.091 → 0.098; 5 · 10⁻⁴
  /// and 2 · 10⁻³ traded logs against each other. 0: off.
  double odometry_heading_kappa = 1e-3;
  double max_odometry_information_theta = 20.0;
  /// The same for translation: σ from |matched − odometry| step (m, the
  /// difference of the two step vectors), x and y information
  /// odometry_translation_kappa / σ², between odometry_information_xy and
  /// max_odometry_information_xy. The fixed pull is far weaker than the data
  /// term, and a sparse scan's match slides along a corridor or past a wall's
  /// mapped end where the odometry was within a few cm: corrected intel,
  /// scans 108–112, −0.43 m along 5 m of corridor against the odometry's
  /// +0.16. From 10 starts with loop closure, ATE medians: edmonton 0.85 →
  /// 0.43 m, infinite-corridor 0.81 → 0.74, intel 0.078 → 0.071, belgioioso
  /// 0.098 → 0.091, but campus 0.32 → 0.43 (it wants a weaker pull: 0.34 at
  /// 5 · 10⁻³). 3 · 10⁻² broke belgioioso (0.36) and let csail accept false
  /// closures, 5 · 10⁻³ and 1.5 · 10⁻² were worse on csail or belgioioso
  /// (docs/BENCHMARKS.md §4). 0: off.
  double odometry_translation_kappa = 1e-2;
  double max_odometry_information_xy = 20.0;
  int odometry_agreement_scans = 50;
  OccupancyUpdate occupancy;             ///< log-odds of hits and misses, clamping
  ScanMatcherOptions matcher;            ///< iterations, damping, step bounds (reflectivity weight set from above)
  IncidenceOptions incidence;            ///< per-beam incidence for the calibration
  /// Self-calibration of a scanner model that has no calibration set: a
  /// sample of readings of map cells (see CalibrationSampler) is collected at
  /// map updates, and selfCalibrate runs once it is ready; reflectivity of
  /// that model is fused from then on (the sample itself included).
  bool self_calibration = true;
  CalibrationSamplerOptions calibration_sample;
  SelfCalibrationOptions self_calibration_fit;
  /// Loop closure with a pose graph (see loop_closure.h); on by default.
  /// Its submaps take resolution_m, occupancy and matcher from here.
  LoopClosureOptions loop_closure;

  /// @throws std::invalid_argument naming the first bad option
  void validate() const;
};

/// Information (x, y: 1/m²; θ: 1/rad²) of a sparse trajectory's odometry
/// prior, from how its odometry's steps agreed with the matches (see
/// Slam2dOptions::odometry_translation_kappa and odometry_heading_kappa); each
/// part is the fixed one (odometry_information_xy / _theta) while fewer than a
/// fifth of odometry_agreement_scans steps were seen, and never less.
/// @param translation_disagreement_m  |matched − odometry| step (m) of the trajectory's newest odometry steps
/// @param heading_disagreement_rad    |matched − odometry| heading step (rad) of the same steps
Eigen::Vector3d odometryPriorInformation(const std::deque<double>& translation_disagreement_m,
                                         const std::deque<double>& heading_disagreement_rad, const Slam2dOptions& options);

/// A scan's robot pose at its stamp.
struct StampedPose2 {
  int64_t stamp_ns = 0;
  Pose2 pose;
};

class Slam2d {
 public:
  /// @throws std::invalid_argument for bad options
  explicit Slam2d(Slam2dOptions options = {});

  /// Sets the calibration used for scans of `model` (replacing self-calibration for it).
  void setCalibration(const std::string& model, IntensityCalibration calibration);
  /// The calibration in use for `model` (set or self-calibrated), if any.
  const IntensityCalibration* calibration(const std::string& model) const;

  /// Processes one scan of `trajectory` (created on first use, starting at
  /// `odometry` when given — robots that share a map must send odometry in
  /// the map frame — else at the origin).
  /// @param odometry  robot base pose from odometry at scan.stamp_ns, when known
  /// @return the robot base pose estimate in the map frame
  /// @throws std::invalid_argument with a clear message for a scan that cannot
  ///         be used (sizes differ, no finite beam, non-finite mount or
  ///         odometry); the state is then unchanged
  Pose2 addScan(const std::string& trajectory, const LaserScan& scan, const std::optional<Pose2>& odometry);
  std::optional<Pose2> pose(const std::string& trajectory) const;
  /// The finest level, for rendering and export.
  const GridMap2d& grid() const { return map_; }
  /// Counts map updates and re-renderings; changes whenever grid() changed.
  uint64_t version() const { return version_; }
  const Slam2dOptions& options() const { return options_; }

  /// Loop closures accepted since the last call: kept by the optimisation
  /// after them and by a later one, or held for
  /// LoopClosureOptions::confirm_after_s of their trajectory's sensor time.
  std::vector<LoopClosure2d> takeLoopClosures();
  /// Accepts the closures still waiting for a second optimisation: call when
  /// the data ended (a log's end), since nothing will test them any more.
  void confirmLoopClosures();
  /// Accepted loop closures a later optimisation dropped, since the last
  /// call (take the accepted ones first: one may be both). Poses as now;
  /// match_submap is empty (the accepted report carried it).
  std::vector<LoopClosure2d> takeWithdrawnLoopClosures();
  /// Every scan's robot pose in scan order, corrected by the pose graph (each
  /// scan rides on the keyframe before it); empty for an unknown trajectory.
  std::vector<StampedPose2> trajectory(const std::string& trajectory) const;
  /// Increments after each optimisation that moved a keyframe beyond
  /// LoopClosureOptions::rerender_shift_* from where the map holds it; grid()
  /// is then re-rendered at their corrected poses from that keyframe on (from
  /// the map copy before it, see rerender_checkpoints; version() changes too).
  /// Smaller corrections move the poses only.
  uint64_t graphVersion() const { return graph_version_; }
  /// Keyframe insertions spent re-rendering the map after corrections (what rerender_checkpoints saves).
  uint64_t rerenderedKeyframes() const { return rerendered_keyframes_; }
  /// Loop closure counters and timing; nullptr when loop closure is off.
  const LoopClosureStats* loopClosureStats() const { return loop_closer_ ? &loop_closer_->stats() : nullptr; }
  size_t keyframeCount() const { return keyframes_.size(); }

 private:
  /// The closures as reported: trajectories by name, scans by stamp, poses as now.
  std::vector<LoopClosure2d> reported(const std::vector<KeyframeClosure>& closures) const;
  struct Trajectory {
    Pose2 pose;
    std::optional<Pose2> odometry;  ///< at the last scan (none when it came without)
    Pose2 last_increment;           ///< motion of the last scan, the prediction without odometry
    Pose2 last_update_pose;         ///< pose at the last map update
    std::optional<double> match_residual;  ///< running mean of the matches' mean residual (see relock_*)
    std::optional<double> scan_motion_m;   ///< running mean of the translation between scans (see sparse_scan_motion_m)
    /// Newest last: |matched − odometry| steps (see odometryPriorInformation).
    std::deque<double> translation_disagreement_m, heading_disagreement_rad;
    size_t index = 0;                      ///< into names_ and scans_
    std::optional<size_t> keyframe;        ///< its newest keyframe
    std::optional<Pose2> slip_pose;        ///< the last scan's pose if the wheels slipped (relock_after_large_step_m)
  };

  /// A scan's pose relative to the keyframe before it (absolute when none).
  struct ScanRecord {
    int64_t stamp_ns = 0;
    std::optional<size_t> keyframe;
    Pose2 relative;
  };

  /// One trajectory's local matching map (see Slam2dOptions::local_map_keyframes).
  struct LocalMap {
    GridMap2d grid;
    std::vector<size_t> keyframes;  ///< indices into keyframes_, for re-rendering
  };

  struct ScannerModel {
    std::optional<IntensityCalibration> calibration;
    std::optional<CalibrationSampler> sampler;  ///< while self-calibration is collecting
    bool tried_full = false;                    ///< one attempt is made once the sample is full
  };

  /// Whether `track`'s scans are sparse_scan_motion_m or more apart (running mean).
  bool sparse(const Trajectory& track) const {
    return track.scan_motion_m && *track.scan_motion_m >= options_.sparse_scan_motion_m;
  }
  /// Self-calibrates `model` from its sample when ready; fuses the sample on success.
  void maybeSelfCalibrate(ScannerModel& model);
  /// After the graph moved keyframes: the map is rendered again from the first
  /// that moved and every trajectory's pose follows its newest keyframe.
  void applyCorrection(const std::vector<std::pair<Pose2, Pose2>>& relative_to_keyframe);
  /// Adds `keyframe` (to be keyframes_[k]) to its trajectory's local maps,
  /// starting and dropping maps as they fill.
  void addToLocalMaps(const Keyframe& keyframe, size_t k, const IntensityCalibration* calibration);
  /// The map a scan of trajectory `index` is matched against.
  const GridMap2d& matchingMap(size_t index) const;
  const IntensityCalibration* calibrationOf(const Keyframe& keyframe) const;

  Slam2dOptions options_;
  GridMap2d map_;
  std::unordered_map<std::string, ScannerModel> models_;
  std::unordered_map<std::string, Trajectory> trajectories_;
  std::vector<std::string> names_;             ///< trajectory names by index
  std::vector<std::vector<ScanRecord>> scans_;  ///< by trajectory index
  /// Every map update's scan; without loop closure only stamp, pose and trajectory are kept.
  std::vector<Keyframe> keyframes_;
  std::vector<std::deque<LocalMap>> local_maps_;  ///< by trajectory index, the front one matched
  std::vector<Pose2> rendered_;  ///< per keyframe, the pose the map holds it at (loop closure only)
  MapCheckpoints checkpoints_;   ///< map_ along the keyframes, where re-rendering can start (loop closure only)
  std::unique_ptr<LoopCloser> loop_closer_;
  uint64_t version_ = 0;
  uint64_t graph_version_ = 0;
  uint64_t rerendered_keyframes_ = 0;
};

}  // namespace rmap::slam2d
