#include "sim/revisit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace rmap::sim {
namespace {

const std::vector<Eigen::Vector2d> kSquare{{0, 0}, {10, 0}, {10, 10}, {0, 10}};

double headingOf(const RevisitFrame& f) {
  const Eigen::Vector3d x = f.pose_world.linear().col(0);
  return std::atan2(x.y(), x.x());
}

TEST(Revisit, DrivesTheLapsAtTheStep) {
  RevisitOptions o;
  o.lateral_offset_m = 0.0;
  o.heading_jitter_rad = 0.0;
  o.corner_radius_m = 1.0;
  const std::vector<RevisitFrame> frames = planRevisits(kSquare, o, 1);
  const double lap_m = 4 * (10.0 - 2.0) + 2 * std::numbers::pi;  // straights plus four quarter circles
  EXPECT_EQ(frames.size(), static_cast<size_t>(std::ceil(2 * lap_m / 0.5)));
  EXPECT_EQ(frames.front().lap, 0);
  EXPECT_EQ(frames.back().lap, 1);
  for (size_t i = 1; i < frames.size(); ++i) {
    const double chord = (frames[i].pose_world.translation() - frames[i - 1].pose_world.translation()).norm();
    EXPECT_LE(chord, 0.5 + 1e-9);
    EXPECT_GT(chord, 0.48);  // arcs shorten the chord a little
    EXPECT_NEAR(frames[i].pose_world.translation().z(), 1.0, 1e-12);
  }
  // Starts after the first corner's arc, heading +x; after the first straight, it turns left.
  EXPECT_NEAR(frames[0].pose_world.translation().x(), 1.0, 1e-9);
  EXPECT_NEAR(headingOf(frames[0]), 0.0, 1e-12);
  EXPECT_NEAR(headingOf(frames[17]), 0.5, 1e-9);               // 0.5 m into the first arc (radius 1 m)
  EXPECT_NEAR(headingOf(frames[20]), std::numbers::pi / 2, 1e-9);  // on the second edge
  EXPECT_NEAR(frames[20].pose_world.translation().x(), 10.0, 1e-9);
}

TEST(Revisit, TruthPairsAreSamePlaceSameHeadingNextLap) {
  RevisitOptions o;
  const std::vector<RevisitFrame> frames = planRevisits(kSquare, o, 4);
  const auto pairs = truthLoopPairs(frames);
  const double lap_m = 4 * (10.0 - 2.0) + 2 * std::numbers::pi;
  ASSERT_FALSE(pairs.empty());
  size_t second_lap = 0;
  for (const RevisitFrame& f : frames) second_lap += f.lap == 1;
  std::vector<bool> has_pair(frames.size(), false);
  for (const auto& [q, r] : pairs) {
    ASSERT_GT(q, r);
    // A whole number of laps apart (the end of a lap meets the start of the next),
    // give or take the 1 m distance (a little more along an arc).
    EXPECT_LE(std::abs(std::remainder(frames[q].travel_m - frames[r].travel_m, lap_m)), 1.2);
    EXPECT_GE(frames[q].travel_m - frames[r].travel_m, 10.0);
    EXPECT_LE((frames[q].pose_world.translation() - frames[r].pose_world.translation()).norm(), 1.0);
    has_pair[q] = true;
  }
  size_t queries = 0;
  for (bool b : has_pair) queries += b;
  EXPECT_GE(queries, second_lap - 2);  // every frame of the second lap revisits the first (maybe not the very last)
  // Opposite headings are not the same view.
  LoopTruthOptions strict;
  strict.max_heading_rad = 1e-6;
  EXPECT_LT(truthLoopPairs(frames, strict).size(), pairs.size() / 10);
}

TEST(Revisit, DeterministicForASeed) {
  const auto a = planRevisits(kSquare, {}, 9), b = planRevisits(kSquare, {}, 9), c = planRevisits(kSquare, {}, 10);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_TRUE(a[30].pose_world.isApprox(b[30].pose_world));
  EXPECT_FALSE(a[30].pose_world.isApprox(c[30].pose_world));
}

TEST(Revisit, BadInputThrows) {
  EXPECT_THROW(planRevisits({{0, 0}, {1, 0}}, {}, 1), std::invalid_argument);
  EXPECT_THROW(planRevisits({{0, 0}, {0, 10}, {10, 10}, {10, 0}}, {}, 1), std::invalid_argument);  // clockwise
  RevisitOptions o;
  o.corner_radius_m = 6.0;
  EXPECT_THROW(planRevisits(kSquare, o, 1), std::invalid_argument);
  o = {};
  o.step_m = 0.0;
  EXPECT_THROW(planRevisits(kSquare, o, 1), std::invalid_argument);
  LoopTruthOptions t;
  t.max_distance_m = -1.0;
  EXPECT_THROW(truthLoopPairs({}, t), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::sim
