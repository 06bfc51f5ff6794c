#include "graph/pose_graph_2d.h"

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rmap::graph {

namespace {

template <typename T>
T wrap(const T& a) {
  using std::floor;
  const T two_pi = T(2.0 * std::numbers::pi);
  return a - two_pi * floor((a + T(std::numbers::pi)) / two_pi);
}

/// Whitened SPA residual: L·[R(θa)ᵀ(p_b − p_a) − t_ab; wrap(θb − θa − θab)], LᵀL = information.
class RelativePoseCost {
 public:
  RelativePoseCost(const Pose2d& measurement, const Eigen::Matrix3d& sqrt_information)
      : measurement_(measurement), sqrt_information_(sqrt_information) {}

  template <typename T>
  bool operator()(const T* a, const T* b, T* residual) const {
    using std::cos;
    using std::sin;
    const T c = cos(a[2]), s = sin(a[2]);
    const T dx = b[0] - a[0], dy = b[1] - a[1];
    Eigen::Matrix<T, 3, 1> r;
    r[0] = c * dx + s * dy - T(measurement_[0]);
    r[1] = -s * dx + c * dy - T(measurement_[1]);
    r[2] = wrap(b[2] - a[2] - T(measurement_[2]));
    Eigen::Map<Eigen::Matrix<T, 3, 1>> out(residual);
    out = sqrt_information_.cast<T>() * r;
    return true;
  }

 private:
  Pose2d measurement_;
  Eigen::Matrix3d sqrt_information_;
};

bool finite(const Eigen::MatrixXd& m) { return m.allFinite(); }

}  // namespace

double wrapAngle(double angle_rad) {
  const double w = wrap(angle_rad);
  return w <= -std::numbers::pi ? w + 2.0 * std::numbers::pi : w;
}

Pose2d compose(const Pose2d& a, const Pose2d& b) {
  const double c = std::cos(a[2]), s = std::sin(a[2]);
  return {a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], wrapAngle(a[2] + b[2])};
}

Pose2d between(const Pose2d& a, const Pose2d& b) {
  const double c = std::cos(a[2]), s = std::sin(a[2]);
  const double dx = b[0] - a[0], dy = b[1] - a[1];
  return {c * dx + s * dy, -s * dx + c * dy, wrapAngle(b[2] - a[2])};
}

void PoseGraphOptions::validate() const {
  if (!(loss_scale > 0.0) || !std::isfinite(loss_scale))
    throw std::invalid_argument("PoseGraphOptions: loss_scale must be finite and > 0");
  if (max_iterations < 1) throw std::invalid_argument("PoseGraphOptions: max_iterations must be ≥ 1");
  if (!(function_tolerance > 0.0)) throw std::invalid_argument("PoseGraphOptions: function_tolerance must be > 0");
}

PoseGraph2d::PoseGraph2d(PoseGraphOptions options) : options_((options.validate(), options)) {}

size_t PoseGraph2d::addNode(const Pose2d& pose) {
  if (!pose.allFinite()) throw std::invalid_argument("PoseGraph2d::addNode: pose is not finite");
  poses_.push_back({pose[0], pose[1], wrapAngle(pose[2])});
  return poses_.size() - 1;
}

size_t PoseGraph2d::addEdge(const Edge2d& edge) {
  const std::string what = "PoseGraph2d::addEdge: ";
  if (edge.from >= poses_.size() || edge.to >= poses_.size())
    throw std::invalid_argument(what + "node index out of range (" + std::to_string(edge.from) + " → " +
                                std::to_string(edge.to) + ", " + std::to_string(poses_.size()) + " nodes)");
  if (edge.from == edge.to) throw std::invalid_argument(what + "an edge must join two different nodes");
  if (!finite(edge.measurement) || !finite(edge.information))
    throw std::invalid_argument(what + "measurement and information must be finite");
  if ((edge.information - edge.information.transpose()).cwiseAbs().maxCoeff() >
      1e-9 * (1.0 + edge.information.cwiseAbs().maxCoeff()))
    throw std::invalid_argument(what + "information must be symmetric");
  if (edge.information.llt().info() != Eigen::Success)
    throw std::invalid_argument(what + "information must be positive definite");
  edges_.push_back(edge);
  enabled_.push_back(1);
  return edges_.size() - 1;
}

void PoseGraph2d::disableEdge(size_t edge) { enabled_.at(edge) = 0; }

Pose2d PoseGraph2d::edgeError(size_t e) const {
  const Edge2d& edge = edges_.at(e);
  return between(edge.measurement, between(poses_[edge.from], poses_[edge.to]));
}

OptimizationSummary PoseGraph2d::optimize() {
  OptimizationSummary summary;
  if (poses_.size() < 2) {
    summary.usable = true;
    return summary;
  }
  std::vector<Pose2d> work = poses_;
  ceres::Problem::Options problem_options;
  // The graph owns neither the costs nor the losses beyond this call: let the problem delete them.
  ceres::Problem problem(problem_options);
  for (size_t e = 0; e < edges_.size(); ++e) {
    if (!enabled_[e]) continue;
    const Edge2d& edge = edges_[e];
    const Eigen::Matrix3d sqrt_information = edge.information.llt().matrixU();
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseCost, 3, 3, 3>(
        new RelativePoseCost(edge.measurement, sqrt_information));
    ceres::LossFunction* loss = nullptr;
    if (edge.robust) {
      const double a = options_.loss_scale;
      loss = options_.loss == RobustLoss::kHuber ? static_cast<ceres::LossFunction*>(new ceres::HuberLoss(a))
                                                 : new ceres::CauchyLoss(a);
    }
    problem.AddResidualBlock(cost, loss, work[edge.from].data(), work[edge.to].data());
  }
  if (problem.HasParameterBlock(work[0].data())) problem.SetParameterBlockConstant(work[0].data());

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = options_.max_iterations;
  solver_options.function_tolerance = options_.function_tolerance;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  ceres::Solver::Summary ceres_summary;
  ceres::Solve(solver_options, &problem, &ceres_summary);

  summary.iterations = static_cast<int>(ceres_summary.iterations.size());
  summary.initial_cost = ceres_summary.initial_cost;
  summary.final_cost = ceres_summary.final_cost;
  summary.usable = ceres_summary.IsSolutionUsable();
  if (summary.usable) {
    for (Pose2d& p : work) p[2] = wrapAngle(p[2]);
    bool all_finite = true;
    for (const Pose2d& p : work) all_finite = all_finite && p.allFinite();
    if (all_finite) {
      poses_ = std::move(work);
    } else {
      summary.usable = false;
    }
  }
  return summary;
}

}  // namespace rmap::graph
