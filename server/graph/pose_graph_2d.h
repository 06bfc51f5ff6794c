#pragma once
/// @file pose_graph_2d.h
/// A 2D pose graph (SPA-like: Konolige et al., IROS 2010) optimised with
/// Ceres. Nodes are planar poses (x, y in metres, θ in radians, map frame);
/// an edge measures the pose of its `to` node in the frame of its `from`
/// node, with an information matrix (inverse covariance, units 1/m², 1/rad²).
/// Loop edges get a robust loss so that a wrong one, outvoted by the rest of
/// the graph, loses its pull instead of bending the map.
///
/// No I/O, no threads (Ceres runs single-threaded). The first node is the
/// gauge: it never moves. Nodes not connected to it keep their poses where no
/// edge pulls them.

#include <Eigen/Core>
#include <cstddef>
#include <vector>

namespace rmap::graph {

/// x (m), y (m), θ (rad).
using Pose2d = Eigen::Vector3d;

/// a ⊕ b: b expressed in a's frame, result in a's parent frame.
Pose2d compose(const Pose2d& a, const Pose2d& b);
/// a⁻¹ ⊕ b: the pose of b in a's frame.
Pose2d between(const Pose2d& a, const Pose2d& b);
/// Wraps an angle to (−π, π].
double wrapAngle(double angle_rad);

struct Edge2d {
  size_t from = 0;
  size_t to = 0;
  Pose2d measurement = Pose2d::Zero();                    ///< pose of `to` in `from`'s frame
  Eigen::Matrix3d information = Eigen::Matrix3d::Identity();  ///< symmetric positive definite
  bool robust = false;                                    ///< robust loss (loop edges)
};

enum class RobustLoss { kHuber, kCauchy };

struct PoseGraphOptions {
  RobustLoss loss = RobustLoss::kHuber;
  /// Scale of the robust loss in whitened units (σ): residuals beyond about
  /// this many standard deviations lose weight.
  double loss_scale = 3.0;
  int max_iterations = 30;
  double function_tolerance = 1e-7;

  /// @throws std::invalid_argument naming the first bad option
  void validate() const;
};

struct OptimizationSummary {
  int iterations = 0;
  double initial_cost = 0.0;  ///< ½ Σ ρ(‖r‖²) before and after
  double final_cost = 0.0;
  bool usable = false;        ///< Ceres ended with a usable solution (poses updated only then)
};

class PoseGraph2d {
 public:
  /// @throws std::invalid_argument for bad options
  explicit PoseGraph2d(PoseGraphOptions options = {});

  /// @return the new node's index
  /// @throws std::invalid_argument for a non-finite pose
  size_t addNode(const Pose2d& pose);
  /// @throws std::invalid_argument for a bad index or edge (non-finite values,
  ///         a self-loop, an information matrix that is not symmetric positive
  ///         definite); the graph is then unchanged
  size_t addEdge(const Edge2d& edge);
  /// Drops an edge from later optimisations (rejected loop closures).
  /// @throws std::out_of_range for a bad index
  void disableEdge(size_t edge);

  size_t nodeCount() const { return poses_.size(); }
  size_t edgeCount() const { return edges_.size(); }
  const Pose2d& pose(size_t node) const { return poses_.at(node); }
  const Edge2d& edge(size_t e) const { return edges_.at(e); }
  bool edgeEnabled(size_t e) const { return enabled_.at(e) != 0; }

  /// Error of an edge at the current poses: measurement⁻¹ ⊕ (from⁻¹ ⊕ to),
  /// translation (m) and angle (rad).
  Pose2d edgeError(size_t e) const;

  /// Optimises every node but the first over the enabled edges (Levenberg–
  /// Marquardt, sparse Cholesky); angles are wrapped afterwards.
  OptimizationSummary optimize();

 private:
  PoseGraphOptions options_;
  std::vector<Pose2d> poses_;
  std::vector<Edge2d> edges_;
  std::vector<char> enabled_;
};

}  // namespace rmap::graph
