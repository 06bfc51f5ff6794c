#pragma once
/// @file trajectory_metrics.h
/// Accuracy metrics of a 2D SLAM trajectory: the relation error of Kümmerle
/// et al. (Autonomous Robots 27(4), 2009), the absolute trajectory error
/// after a best-fit rigid alignment, and the relative pose error over a
/// travelled distance. Pure functions, no I/O.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "datasets/slam_relations.h"
#include "slam2d/pose2.h"

namespace rmap::bench {

/// Summary of non-negative errors; NaN fields when count is 0.
struct ErrorStats {
  size_t count = 0;
  double mean = 0.0;
  double std = 0.0;   ///< population standard deviation (divides by count)
  double rmse = 0.0;
  double max = 0.0;
};

ErrorStats errorStats(const std::vector<double>& errors);

struct StampedPose2 {
  int64_t stamp_ns = 0;
  slam2d::Pose2 pose;
};

struct RelationErrors {
  size_t relations_used = 0;  ///< relations whose two stamps are both in the trajectory
  ErrorStats translation_m;   ///< |t(e)|, e = δ_ref⁻¹ · δ_est, δ_est = pose(t1)⁻¹ · pose(t2)
  ErrorStats rotation_rad;    ///< |θ(e)|
};

/// Relation error (Kümmerle et al. 2009): every relation whose two
/// timestamps equal (to the nanosecond) stamps of `trajectory` is compared
/// with the estimated motion between those poses; the others are skipped and
/// not counted. A stamp present more than once in `trajectory` takes its
/// first pose.
RelationErrors relationErrors(const std::vector<StampedPose2>& trajectory,
                              const std::vector<datasets::SlamRelation>& relations);

/// The rigid motion T minimising Σ |T·p_est,i − p_ref,i|² over the positions
/// (closed form: centroids and the 2×2 cross-covariance, Umeyama without
/// scale). Identity for fewer than one pair; a pure translation for one.
/// @throws std::invalid_argument when the sizes differ
slam2d::Pose2 alignRigid2d(const std::vector<slam2d::Pose2>& estimate, const std::vector<slam2d::Pose2>& reference);

/// Absolute trajectory error: distances |T·p_est,i − p_ref,i| after the
/// alignment above (metres); rmse is the usual ATE figure.
/// @throws std::invalid_argument when the sizes differ
ErrorStats absoluteTrajectoryError(const std::vector<slam2d::Pose2>& estimate,
                                   const std::vector<slam2d::Pose2>& reference);

struct RelativePoseErrors {
  ErrorStats translation_m;  ///< |t(e)|, e = (ref_i⁻¹ ref_j)⁻¹ · (est_i⁻¹ est_j)
  ErrorStats rotation_rad;   ///< |θ(e)|
};

/// Relative pose error over `distance_m` of travel: for every pose i, j is
/// the first later pose whose path length along the reference from i reaches
/// distance_m; poses with no such j are skipped. Independent of any global
/// alignment, so drift shows per metre travelled.
/// @throws std::invalid_argument when the sizes differ or distance_m ≤ 0
RelativePoseErrors relativePoseError(const std::vector<slam2d::Pose2>& estimate,
                                     const std::vector<slam2d::Pose2>& reference, double distance_m);

}  // namespace rmap::bench
