#pragma once
/// @file correlative_matcher.h
/// Exact correlative scan matching by branch and bound (Olson, "Real-time
/// correlative scan matching", ICRA 2009), for loop-closure search of a scan
/// against an older submap over a large window.
///
/// The search lattice (SearchLattice) is every rotation θ_k = θ_c + k·δ,
/// |k| ≤ K, times every translation t_c + (i, j)·resolution, |i|, |j| ≤ L,
/// around the centre pose c. At rotation k a point p falls in the cell
/// c_k(p) = ProbabilityRaster::cellOf(R(θ_k)·p + t_c), and the score of
/// lattice pose (k, i, j) is the mean over the points of the raster value at
/// c_k(p) + (i, j): the mean occupancy probability of the cells the scan's
/// endpoints hit, in [0, 1].
///
/// The matcher precomputes max-pooled levels of the raster (level h holds,
/// per cell, the maximum over the 2^h × 2^h cells above and to the right of
/// it, rounded up to 1/255 in a byte), so the score of a 2^h × 2^h block of
/// translations is bounded from above by one lookup per point, and searches
/// depth first, best bound first, pruning blocks whose bound cannot beat the
/// best pose found or reach min_score; lattice poses that pass their level-0
/// bound get their exact score from the float raster. At the coarsest level,
/// groups of consecutive rotations are bounded together first (per point, the
/// box of its cells over the group), so most rotations of a wide angular
/// window are never bounded one by one.
/// The result equals brute force over the lattice (same score; the same pose
/// unless several tie).

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "slam2d/pose2.h"
#include "slam2d/probability_raster.h"

namespace rmap::slam2d {

struct CorrelativeMatcherOptions {
  /// Precomputed levels including the raster itself; the coarsest block of
  /// translations is 2^(branch_levels−1) cells on a side. 1 = brute force. [1, 16]
  int branch_levels = 7;
  /// Rotation step δ (rad), > 0; 0 = from the scan's extent: the step that
  /// moves the farthest point by one cell (δ = acos(1 − r²/(2·d_max²))).
  double angular_step_rad = 0.0;
  /// Windows up to ±fast_window_m read the pooled levels without bounds
  /// checks for every point whose cells stay within this margin of the raster
  /// (a larger window is as exact, slower). The levels are padded by it on
  /// every side: memory (width + 2·margin)·(height + 2·margin)·branch_levels
  /// bytes, margin = fast_window_m / resolution + 2^(branch_levels−1). ≥ 0.
  double fast_window_m = 5.0;

  /// @throws std::invalid_argument naming the first bad parameter
  void validate() const;
};

/// Translations a search leaves out: those within radius_m of center_m (map
/// frame, at any rotation). A search around a found pose with its
/// neighbourhood left out finds a rival: another place the scan fits nearly
/// as well.
struct ExcludedDisk {
  Eigen::Vector2d center_m = Eigen::Vector2d::Zero();
  double radius_m = 0.0;
};

struct CorrelativeMatch {
  Pose2 pose;          ///< robot pose in the raster's (map) frame, on the lattice
  double score = 0.0;  ///< mean occupancy probability over the points, 0..1
};

/// The lattice match() searches for given points and windows.
struct SearchLattice {
  double angular_step_rad = 0.0;  ///< δ
  int angular_steps = 0;          ///< K = floor(window_rad / δ): rotations θ_c + k·δ, |k| ≤ K
  int linear_steps = 0;           ///< L = floor(window_m / resolution): shifts (i, j)·resolution, |i|, |j| ≤ L
};

class CorrelativeMatcher {
 public:
  /// Largest accepted window half-width in cells (L), which bounds memory and
  /// keeps cell arithmetic far from integer overflow.
  static constexpr int kMaxLinearSteps = 1 << 14;
  /// Largest accepted points × rotations of one search: the discretised scan
  /// takes about 12 bytes per point and rotation (2^24: 200 MB).
  static constexpr int64_t kMaxPointRotations = int64_t{1} << 24;

  /// Precomputes the max-pooled levels of `raster` (O(cells · levels) time
  /// and memory).
  /// @throws std::invalid_argument for a raster that fails validate() or bad options
  explicit CorrelativeMatcher(ProbabilityRaster raster, CorrelativeMatcherOptions options = {});

  /// The best lattice pose within ±window_m (x and y) and ±window_rad of
  /// `center` whose score is ≥ min_score (the pruning uses it: a higher
  /// min_score is faster); nullopt when none reaches it or `points_robot` is
  /// empty. Points are scan endpoints in the robot frame (m).
  /// @param window_m  ≥ 0, at most kMaxLinearSteps cells
  /// @param window_rad  in [0, π]
  /// @param min_score  in [0, 1]
  /// @throws std::invalid_argument for a bad window or min_score, a
  ///         non-finite point or centre, or more than kMaxPointRotations
  ///         points × rotations (far points make the step fine: subsample, or
  ///         set angular_step_rad)
  /// @param excluded  lattice poses whose translation lies in this disk are not candidates
  /// Concurrent calls are safe (no state changes).
  std::optional<CorrelativeMatch> match(std::span<const Eigen::Vector2d> points_robot, const Pose2& center,
                                        double window_m, double window_rad, double min_score,
                                        const std::optional<ExcludedDisk>& excluded = std::nullopt) const;

  /// A lattice pose outside `excluded` scoring ≥ min_score, the first the
  /// search meets (not the best: it stops there, far sooner than match() when
  /// many poses qualify); nullopt when none does. Same arguments and errors as match().
  std::optional<CorrelativeMatch> firstAtLeast(std::span<const Eigen::Vector2d> points_robot, const Pose2& center,
                                               double window_m, double window_rad, double min_score,
                                               const std::optional<ExcludedDisk>& excluded = std::nullopt) const;

  /// The lattice match() would search (same validation, empty points allowed:
  /// then the extent-derived step is π).
  SearchLattice lattice(std::span<const Eigen::Vector2d> points_robot, double window_m, double window_rad) const;

  const ProbabilityRaster& raster() const { return raster_; }
  const CorrelativeMatcherOptions& options() const { return options_; }

 private:
  struct Candidate;
  struct Rotation;
  struct RotationGroup;
  struct Restriction;

  std::optional<CorrelativeMatch> search(std::span<const Eigen::Vector2d> points_robot, const Pose2& center,
                                         double window_m, double window_rad, double min_score,
                                         const std::optional<ExcludedDisk>& excluded, bool first_only) const;

  std::vector<Rotation> discretise(std::span<const Eigen::Vector2d> points_robot, const Pose2& center,
                                   const SearchLattice& lattice) const;
  /// Exact lattice score of shift (dx, dy) cells at one rotation.
  double scoreAt(const Rotation& rotation, int dx, int dy) const;
  /// Quantised bound sum (units of 1/255, h ≥ 0) of the 2^h block of shifts from
  /// (dx, dy); may stop early with any value below `need` once it cannot reach it.
  uint32_t boundAt(int h, const Rotation& rotation, int dx, int dy, uint32_t need) const;
  /// Groups of `size` consecutive rotations for bounds at level `top` over shifts within ±reach.
  std::vector<RotationGroup> group(const std::vector<Rotation>& rotations, int size, int top, int reach) const;
  /// Quantised bound sum of a 2^h block of shifts from (dx, dy) over a group's rotations (as boundAt).
  uint32_t groupBoundAt(int h, const RotationGroup& group, int dx, int dy, uint32_t need) const;
  /// The least bound sum of a block that may hold a pose scoring `score`.
  static uint32_t needFor(double score, size_t points);
  /// Depth-first, best bound first, below `block` (level ≥ 1); `best` holds the best pose so far.
  void descend(const std::vector<Rotation>& rotations, const Candidate& block, int linear_steps, double min_score,
               const Restriction& restriction, std::optional<Candidate>& best) const;

  /// Index of raster cell (x, y) in the padded layout of the pooled levels.
  int64_t index(int x, int y) const {
    return (static_cast<int64_t>(y) + pad_) * stride_ + (static_cast<int64_t>(x) + pad_);
  }

  ProbabilityRaster raster_;
  CorrelativeMatcherOptions options_;
  uint8_t outside_q_ = 0;  ///< outside_p quantised up
  /// Layout shared by the pooled levels: stored cell (sx, sy) is raster cell
  /// (sx − pad, sy − pad), stride × rows cells, pad on every side.
  int pad_ = 0, stride_ = 0, rows_ = 0;
  /// levels_[h] is pooled level h: per cell (x, y) the maximum of the raster
  /// over [x, x + 2^h) × [y, y + 2^h) (outside_p off the raster), quantised up
  /// to multiples of 1/255 (level 0 screens lattice poses before their exact score).
  std::vector<std::vector<uint8_t>> levels_;
};

}  // namespace rmap::slam2d
