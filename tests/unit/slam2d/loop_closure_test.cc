#include "slam2d/loop_closure.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "sim_scans.h"
#include "slam2d/slam2d.h"

namespace rmap::slam2d {
namespace {

class SimulatedLoop : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    world_ = new sim::VoxelWorld(testing::simBuilding());
    tour_ = new std::vector<Pose2>(testing::simTour(*world_, 240, 0.25));
  }
  static void TearDownTestSuite() {
    delete world_;
    delete tour_;
  }

  /// The first return of the tour to where it was at least `min_gap` poses
  /// before (within 0.5 m): [first visit, return].
  static std::pair<size_t, size_t> firstLoop(size_t min_gap) {
    for (size_t j = min_gap; j < tour_->size(); ++j)
      for (size_t i = 0; i + min_gap <= j; ++i)
        if (((*tour_)[i].translation() - (*tour_)[j].translation()).norm() < 0.5) return {i, j};
    return {0, 0};
  }

  /// Odometry with a heading bias (2° per metre) and 2 % scale error.
  static std::vector<Pose2> biasedOdometry(const std::vector<Pose2>& truth) {
    std::vector<Pose2> odo{truth.front()};
    for (size_t k = 1; k < truth.size(); ++k) {
      Pose2 d = between(truth[k - 1], truth[k]);
      const double len = d.translation().norm();
      d.x_m *= 1.02;
      d.theta_rad += 0.035 * len;
      odo.push_back(odo.back() * d);
    }
    return odo;
  }

  /// A scan that only sees ±20° ahead and 2.5 m far: the matcher barely
  /// constrains the pose and the biased odometry drifts it.
  static LaserScan blinkered(LaserScan scan) {
    for (size_t i = 0; i < scan.ranges_m.size(); ++i)
      if (std::abs(scan.angles_rad[i]) > 0.35 || scan.ranges_m[i] > 2.5f) scan.ranges_m[i] = NAN;
    return scan;
  }

  static sim::VoxelWorld* world_;
  static std::vector<Pose2>* tour_;
};
sim::VoxelWorld* SimulatedLoop::world_ = nullptr;
std::vector<Pose2>* SimulatedLoop::tour_ = nullptr;

double rmsError(const std::vector<StampedPose2>& estimate, const std::vector<Pose2>& truth) {
  double sum = 0.0;
  for (size_t k = 0; k < truth.size(); ++k) sum += (estimate[k].pose.translation() - truth[k].translation()).squaredNorm();
  return std::sqrt(sum / double(truth.size()));
}

TEST_F(SimulatedLoop, ClosingTheLoopEndsCloserToTruth) {
  const auto [first, back] = firstLoop(60);
  ASSERT_GT(back, first) << "the tour must come back to a place it saw";
  std::vector<Pose2> truth = testing::smoothTurns(std::vector<Pose2>(tour_->begin(), tour_->begin() + back + 12), 0.1);
  const std::vector<Pose2> odo = biasedOdometry(truth);
  const sim::Laser2dModel model = sim::Laser2dModel::sickLike();
  auto run = [&](bool loop_closure) {
    Slam2dOptions options;
    options.loop_closure.enabled = loop_closure;
    Slam2d slam(options);
    std::mt19937_64 rng(31);
    const size_t blind_from = truth.size() / 4, blind_to = truth.size() / 2;
    for (size_t k = 0; k < truth.size(); ++k) {
      LaserScan scan = testing::simScan(*world_, truth[k], model, rng, int64_t(k) * 100'000'000);
      if (k >= blind_from && k < blind_to) scan = blinkered(std::move(scan));
      slam.addScan("robot", scan, odo[k]);
    }
    return slam;
  };
  const Slam2d without = run(false);
  Slam2d with = run(true);
  const std::vector<StampedPose2> corrected = with.trajectory("robot");
  ASSERT_EQ(corrected.size(), truth.size());
  const double error_without = rmsError(without.trajectory("robot"), truth);
  const double error_with = rmsError(corrected, truth);
  EXPECT_GT(error_without, 0.15) << "the blind stretch must make the front end drift";
  EXPECT_LT(error_with, 0.6 * error_without);
  EXPECT_GT(with.graphVersion(), 0u);
  EXPECT_EQ(without.graphVersion(), 0u);
  const std::vector<LoopClosure2d> closures = with.takeLoopClosures();
  ASSERT_FALSE(closures.empty());
  for (const LoopClosure2d& c : closures) {
    EXPECT_EQ(c.query_trajectory, "robot");
    EXPECT_GT(c.query_stamp_ns, c.match_stamp_ns);
    EXPECT_GE(c.score, with.options().loop_closure.min_score);
  }
  EXPECT_TRUE(with.takeLoopClosures().empty()) << "taken closures are not returned again";
  EXPECT_TRUE(with.trajectory("nobody").empty());
}

TEST_F(SimulatedLoop, ClosesBetweenTwoTrajectories) {
  const sim::Laser2dModel model = sim::Laser2dModel::sickLike();
  std::mt19937_64 rng(32);
  Slam2d slam;
  const std::vector<Pose2> a = testing::smoothTurns(std::vector<Pose2>(tour_->begin(), tour_->begin() + 120), 0.1);
  for (size_t k = 0; k < a.size(); ++k)
    slam.addScan("a", testing::simScan(*world_, a[k], model, rng, int64_t(k) * 100'000'000), a[k]);
  slam.takeLoopClosures();  // a's own
  // Robot b drives a's first stretch again, its odometry frame 0.5 m and 8° off the map frame:
  // beyond what the front end's first match corrects.
  const Pose2 offset{0.4, -0.3, 0.14};
  const std::vector<Pose2> b = testing::smoothTurns(std::vector<Pose2>(tour_->begin() + 10, tour_->begin() + 50), 0.1);
  std::vector<LoopClosure2d> closures;
  for (size_t k = 0; k < b.size(); ++k) {
    slam.addScan("b", testing::simScan(*world_, b[k], model, rng, int64_t(1000 + k) * 100'000'000), offset * b[k]);
    for (LoopClosure2d& c : slam.takeLoopClosures()) closures.push_back(c);
  }
  size_t cross = 0;
  for (const LoopClosure2d& c : closures) cross += c.query_trajectory == "b" && c.match_trajectory == "a";
  EXPECT_GT(cross, 0u);
  const Pose2 end = *slam.pose("b");
  EXPECT_LT((end.translation() - b.back().translation()).norm(), 0.1);
  EXPECT_LT(std::abs(normalizeAngle(end.theta_rad - b.back().theta_rad)), 0.03);
}

TEST(LoopClosureOptions, BadOptionsThrow) {
  const auto throws = [](auto change) {
    Slam2dOptions options;
    change(options.loop_closure);
    EXPECT_THROW(Slam2d{options}, std::invalid_argument);
  };
  throws([](LoopClosureOptions& o) { o.submap_keyframes = 1; });
  throws([](LoopClosureOptions& o) { o.min_score = 0.0; });
  throws([](LoopClosureOptions& o) { o.min_score = 1.5; });
  throws([](LoopClosureOptions& o) { o.max_window_m = o.window_m / 2; });
  throws([](LoopClosureOptions& o) { o.window_rad = -0.1; });
  throws([](LoopClosureOptions& o) { o.loop_sigma_m = 0.0; });
  throws([](LoopClosureOptions& o) { o.sequential_sigma_rad = NAN; });
  throws([](LoopClosureOptions& o) { o.optimize_every_keyframes = 0; });
  throws([](LoopClosureOptions& o) { o.graph.loss_scale = -1.0; });
  throws([](LoopClosureOptions& o) { o.submap.correlative.branch_levels = 0; });
  // Off, options are still checked: turning it on later must not be the first time they are.
  throws([](LoopClosureOptions& o) {
    o.enabled = false;
    o.max_candidates = 0;
  });
  EXPECT_NO_THROW(LoopCloser{LoopClosureOptions{}});
}

}  // namespace
}  // namespace rmap::slam2d
