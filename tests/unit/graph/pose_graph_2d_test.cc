#include "graph/pose_graph_2d.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

namespace rmap::graph {
namespace {

constexpr double kPi = std::numbers::pi;

/// A square of side 4 m driven counter-clockwise in 0.5 m steps, turning 90° at corners.
std::vector<Pose2d> squareTruth() {
  std::vector<Pose2d> truth;
  Pose2d p = Pose2d::Zero();
  for (int side = 0; side < 4; ++side) {
    for (int step = 0; step < 8; ++step) {
      truth.push_back(p);
      p = compose(p, {0.5, 0.0, 0.0});
    }
    p = compose(p, {0.0, 0.0, kPi / 2});
  }
  truth.push_back(p);  // back at the start, heading 0 again
  return truth;
}

Eigen::Matrix3d information(double sigma_m, double sigma_rad) {
  return Eigen::Vector3d(1 / (sigma_m * sigma_m), 1 / (sigma_m * sigma_m), 1 / (sigma_rad * sigma_rad)).asDiagonal();
}

/// Odometry with a heading bias and noise, chained from the first pose: the nodes start there.
PoseGraph2d drifted(const std::vector<Pose2d>& truth, PoseGraphOptions options = {}) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.01);
  PoseGraph2d graph(options);
  Pose2d odometry = truth.front();
  graph.addNode(odometry);
  for (size_t i = 1; i < truth.size(); ++i) {
    Pose2d step = between(truth[i - 1], truth[i]);
    step += Pose2d(noise(rng), noise(rng), 0.02 + noise(rng));  // ≈ 1° of heading bias per step
    odometry = compose(odometry, step);
    graph.addNode(odometry);
    graph.addEdge({i - 1, i, step, information(0.02, 0.02), false});
  }
  return graph;
}

double maxPositionError(const PoseGraph2d& graph, const std::vector<Pose2d>& truth) {
  double worst = 0.0;
  for (size_t i = 0; i < truth.size(); ++i)
    worst = std::max(worst, (graph.pose(i).head<2>() - truth[i].head<2>()).norm());
  return worst;
}

TEST(PoseGraph2d, ClosesASquareLoopFromNoisyOdometryAndOneLoopEdge) {
  const std::vector<Pose2d> truth = squareTruth();
  PoseGraph2d graph = drifted(truth);
  const double before = maxPositionError(graph, truth);
  ASSERT_GT(before, 1.0);  // the heading bias bends the square open
  // The last pose sees the first: they are the same place.
  graph.addEdge({0, truth.size() - 1, between(truth.front(), truth.back()), information(0.01, 0.005), true});
  const OptimizationSummary summary = graph.optimize();
  ASSERT_TRUE(summary.usable);
  EXPECT_LT(summary.final_cost, summary.initial_cost);
  EXPECT_LT(maxPositionError(graph, truth), 0.15);
  EXPECT_LT(graph.edgeError(graph.edgeCount() - 1).head<2>().norm(), 0.05);
  // The first node is the gauge.
  EXPECT_EQ(graph.pose(0), truth.front());
}

TEST(PoseGraph2d, RobustLossIgnoresOneWrongLoopEdge) {
  const std::vector<Pose2d> truth = squareTruth();
  PoseGraphOptions cauchy;
  cauchy.loss = RobustLoss::kCauchy;
  cauchy.loss_scale = 1.0;
  PoseGraph2d graph = drifted(truth, cauchy);
  // Correct loops from the last side back to the first, and one wrong: 2 m and 30° off.
  const size_t n = truth.size();
  for (size_t k = 0; k < 4; ++k)
    graph.addEdge({k, n - 1 - k, between(truth[k], truth[n - 1 - k]), information(0.02, 0.01), true});
  const size_t wrong = graph.addEdge(
      {16, n - 3, compose(between(truth[16], truth[n - 3]), {2.0, 0.0, 0.5}), information(0.02, 0.01), true});
  ASSERT_TRUE(graph.optimize().usable);
  EXPECT_LT(maxPositionError(graph, truth), 0.2);
  // The wrong edge stays far from satisfied: a check after optimisation can reject it.
  EXPECT_GT(graph.edgeError(wrong).head<2>().norm(), 1.0);
  for (size_t e = graph.edgeCount() - 5; e < wrong; ++e) EXPECT_LT(graph.edgeError(e).head<2>().norm(), 0.1);

  // Huber (the default) only caps its pull: the map bends some, but the wrong
  // edge still has by far the largest error, which is what the check uses.
  PoseGraph2d huber = drifted(truth);
  for (size_t k = 0; k < 4; ++k)
    huber.addEdge({k, n - 1 - k, between(truth[k], truth[n - 1 - k]), information(0.02, 0.01), true});
  huber.addEdge({16, n - 3, compose(between(truth[16], truth[n - 3]), {2.0, 0.0, 0.5}), information(0.02, 0.01), true});
  ASSERT_TRUE(huber.optimize().usable);
  for (size_t e = huber.edgeCount() - 5; e < wrong; ++e)
    EXPECT_LT(4 * huber.edgeError(e).head<2>().norm(), huber.edgeError(wrong).head<2>().norm());

  // Without the robust loss, the same wrong edge bends the map.
  PoseGraph2d plain = drifted(truth);
  for (size_t k = 0; k < 4; ++k)
    plain.addEdge({k, n - 1 - k, between(truth[k], truth[n - 1 - k]), information(0.02, 0.01), false});
  plain.addEdge({16, n - 3, compose(between(truth[16], truth[n - 3]), {2.0, 0.0, 0.5}), information(0.02, 0.01), false});
  ASSERT_TRUE(plain.optimize().usable);
  EXPECT_GT(maxPositionError(plain, truth), 0.3);

  // Disabling it (after the check) restores the square.
  graph.disableEdge(wrong);
  ASSERT_TRUE(graph.optimize().usable);
  EXPECT_LT(maxPositionError(graph, truth), 0.15);
}

TEST(PoseGraph2d, ComposeAndBetweenAreInverse) {
  const Pose2d a(1.0, -2.0, 3.0), b(-0.5, 0.25, -2.5);
  const Pose2d ab = between(a, b);
  EXPECT_NEAR((compose(a, ab) - Pose2d(b[0], b[1], wrapAngle(b[2]))).norm(), 0.0, 1e-12);
  EXPECT_NEAR(wrapAngle(3 * kPi), kPi, 1e-12);
  EXPECT_NEAR(wrapAngle(-kPi), kPi, 1e-12);
}

TEST(PoseGraph2d, RejectsBadInputAndOptions) {
  PoseGraph2d graph;
  graph.addNode(Pose2d::Zero());
  graph.addNode({1.0, 0.0, 0.0});
  EXPECT_THROW(graph.addNode({NAN, 0.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(graph.addEdge({0, 2, Pose2d::Zero(), Eigen::Matrix3d::Identity(), false}), std::invalid_argument);
  EXPECT_THROW(graph.addEdge({1, 1, Pose2d::Zero(), Eigen::Matrix3d::Identity(), false}), std::invalid_argument);
  EXPECT_THROW(graph.addEdge({0, 1, Pose2d(INFINITY, 0, 0), Eigen::Matrix3d::Identity(), false}),
               std::invalid_argument);
  Eigen::Matrix3d asymmetric = Eigen::Matrix3d::Identity();
  asymmetric(0, 1) = 0.5;
  EXPECT_THROW(graph.addEdge({0, 1, Pose2d::Zero(), asymmetric, false}), std::invalid_argument);
  EXPECT_THROW(graph.addEdge({0, 1, Pose2d::Zero(), -Eigen::Matrix3d::Identity(), false}), std::invalid_argument);
  EXPECT_EQ(graph.nodeCount(), 2u);
  EXPECT_EQ(graph.edgeCount(), 0u);
  EXPECT_THROW(graph.disableEdge(0), std::out_of_range);

  PoseGraphOptions bad;
  bad.loss_scale = 0.0;
  EXPECT_THROW(PoseGraph2d{bad}, std::invalid_argument);
  bad = {};
  bad.max_iterations = 0;
  EXPECT_THROW(PoseGraph2d{bad}, std::invalid_argument);
}

}  // namespace
}  // namespace rmap::graph
