#include "slam2d/occupancy_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace rmap::slam2d {
namespace {

const OccupancyUpdate kUpdate;  // hit +1.0, miss −0.4, clamped to [−2, 3.5]

float prob(float l) { return 1.0f / (1.0f + std::exp(-l)); }

TEST(OccupancyGrid, RayMarksCrossedCellsFreeAndTheEndOccupied) {
  OccupancyGrid grid(1.0);
  const std::vector<Ray> rays{{{3.5, 0.5}, true}};
  grid.insert({0.5, 0.5}, rays, kUpdate, 100.0);
  for (int x = 0; x < 3; ++x) EXPECT_FLOAT_EQ(grid.logOdds({x, 0}), kUpdate.miss_log_odds) << x;
  EXPECT_FLOAT_EQ(grid.logOdds({3, 0}), kUpdate.hit_log_odds);
  EXPECT_FLOAT_EQ(grid.probability({3, 0}), prob(kUpdate.hit_log_odds));
  EXPECT_TRUE(std::isnan(grid.logOdds({4, 0})));
  EXPECT_TRUE(std::isnan(grid.probability({0, 1})));
  EXPECT_EQ(grid.knownCells().min(), Eigen::Vector2i(0, 0));
  EXPECT_EQ(grid.knownCells().max(), Eigen::Vector2i(3, 0));
}

TEST(OccupancyGrid, OneScanChangesACellOnceAndAHitWinsOverAMiss) {
  OccupancyGrid grid(1.0);
  // The first ray crosses (2, 0) and (1, 0); the second ends in (2, 0); the third crosses (1, 0) again.
  const std::vector<Ray> rays{{{4.5, 0.5}, true}, {{2.5, 0.5}, true}, {{1.9, 0.5}, false}};
  grid.insert({0.5, 0.5}, rays, kUpdate, 100.0);
  EXPECT_FLOAT_EQ(grid.logOdds({2, 0}), kUpdate.hit_log_odds);
  EXPECT_FLOAT_EQ(grid.logOdds({1, 0}), kUpdate.miss_log_odds);
  EXPECT_FLOAT_EQ(grid.logOdds({4, 0}), kUpdate.hit_log_odds);
}

TEST(OccupancyGrid, EvidenceIsClampedAndRaysAreCutAtTheMaximumRange) {
  OccupancyGrid grid(1.0);
  const std::vector<Ray> rays{{{5.5, 0.5}, true}};
  for (int i = 0; i < 20; ++i) grid.insert({0.5, 0.5}, rays, kUpdate, 100.0);
  EXPECT_FLOAT_EQ(grid.logOdds({5, 0}), kUpdate.max_log_odds);
  EXPECT_FLOAT_EQ(grid.logOdds({2, 0}), kUpdate.min_log_odds);
  OccupancyGrid cut(1.0);
  cut.insert({0.5, 0.5}, rays, kUpdate, 3.0);  // ends at x = 3.5: free up to there, nothing occupied
  EXPECT_FLOAT_EQ(cut.logOdds({3, 0}), kUpdate.miss_log_odds);
  EXPECT_TRUE(std::isnan(cut.logOdds({5, 0})));
}

TEST(OccupancyGrid, WithoutMissEvidenceOnlyTheBeamsEndsAreDrawn) {
  OccupancyUpdate ends_only = kUpdate;
  ends_only.miss_log_odds = 0.0f;
  OccupancyGrid grid(1.0);
  // A return at (3, 0), a beam without one ending in (0, 2), a return beyond the range cut.
  const std::vector<Ray> rays{{{3.5, 0.5}, true}, {{0.5, 2.5}, false}, {{0.5, 9.5}, true}};
  grid.insert({0.5, 0.5}, rays, ends_only, 5.0);
  EXPECT_FLOAT_EQ(grid.logOdds({3, 0}), kUpdate.hit_log_odds);
  for (const Eigen::Vector2i& cell : {Eigen::Vector2i(1, 0), Eigen::Vector2i(2, 0), Eigen::Vector2i(0, 2),
                                     Eigen::Vector2i(0, 5), Eigen::Vector2i(0, 9)})
    EXPECT_TRUE(std::isnan(grid.logOdds(cell))) << cell.transpose() << ": no evidence, so never known";
  EXPECT_EQ(grid.knownCells().min(), Eigen::Vector2i(3, 0));
  EXPECT_EQ(grid.knownCells().max(), Eigen::Vector2i(3, 0));
}

TEST(OccupancyGrid, GrowsInEveryDirection) {
  OccupancyGrid grid(0.05);
  const std::vector<Ray> rays{{{40.01, 0.01}, true}, {{-39.99, 0.01}, true}, {{0.01, 40.01}, true},
                              {{0.01, -39.99}, true}, {{-30.01, -30.01}, true}};
  grid.insert({0.01, 0.01}, rays, kUpdate, 100.0);
  for (const Ray& r : rays) EXPECT_FLOAT_EQ(grid.logOdds(grid.cellOf(r.end_m)), kUpdate.hit_log_odds);
  const Eigen::AlignedBox2i box = grid.knownCells();
  EXPECT_EQ(box.min(), Eigen::Vector2i(-800, -800));
  EXPECT_EQ(box.max(), Eigen::Vector2i(800, 800));
  EXPECT_FLOAT_EQ(grid.logOdds(grid.cellOf({20.0, 0.01})), kUpdate.miss_log_odds);
  EXPECT_FLOAT_EQ(grid.logOdds(grid.cellOf({-15.02, -15.02})), kUpdate.miss_log_odds);
}

TEST(OccupancyGrid, BilinearValueSitsAtCellCentres) {
  OccupancyGrid grid(0.5);
  grid.insert({0.25, 0.25}, std::vector<Ray>{{{1.75, 0.25}, true}}, kUpdate, 100.0);  // cells 0..2 free, 3 hit
  const float free = prob(kUpdate.miss_log_odds), wall = prob(kUpdate.hit_log_odds);
  EXPECT_NEAR(grid.sample({1.75, 0.25}).value, wall, 1e-6);
  EXPECT_NEAR(grid.sample({1.25, 0.25}).value, free, 1e-6);
  // Halfway between the centres of cells 2 and 3: the mean, and the slope per metre.
  const OccupancyGrid::Sample mid = grid.sample({1.5, 0.25});
  EXPECT_NEAR(mid.value, 0.5f * (free + wall), 1e-6);
  EXPECT_NEAR(mid.gradient_per_m.x(), (wall - free) / 0.5f, 1e-5);
  // Row 1 is unknown (value 0): going up the value falls.
  EXPECT_NEAR(mid.gradient_per_m.y(), -0.5f * (free + wall) / 0.5f, 1e-5);
  // Halfway up to the unknown row: half the value.
  EXPECT_NEAR(grid.sample({1.75, 0.5}).value, 0.5f * wall, 1e-6);
  // Far from anything known: zero.
  const OccupancyGrid::Sample none = grid.sample({100.0, -100.0});
  EXPECT_EQ(none.value, 0.0f);
  EXPECT_EQ(none.gradient_per_m, Eigen::Vector2f::Zero());
}

TEST(OccupancyGrid, ReadsProbabilityAboveAFloor) {
  OccupancyUpdate update = kUpdate;
  update.value_floor_probability = 0.3f;
  OccupancyGrid grid(0.5);
  grid.insert({0.25, 0.25}, std::vector<Ray>{{{1.75, 0.25}, true}}, update, 100.0);  // cells 0..2 free, 3 hit
  EXPECT_FLOAT_EQ(grid.logOdds({2, 0}), update.miss_log_odds) << "the evidence itself is unchanged";
  EXPECT_NEAR(grid.sample({1.25, 0.25}).value, (prob(update.miss_log_odds) - 0.3f) / 0.7f, 1e-6);
  EXPECT_NEAR(grid.sample({1.75, 0.25}).value, (prob(update.hit_log_odds) - 0.3f) / 0.7f, 1e-6);
  for (int k = 0; k < 2; ++k) grid.insert({0.25, 0.25}, std::vector<Ray>{{{1.75, 0.25}, true}}, update, 100.0);
  EXPECT_EQ(grid.sample({1.25, 0.25}).value, 0.0f) << "crossed three times (p = 0.23): read as unknown";
}

TEST(OccupancyGrid, GradientMatchesFiniteDifferencesAcrossChunkBorders) {
  OccupancyGrid grid(0.1);
  // A fan of rays over a chunk border (64 cells = 6.4 m) in x and y.
  std::vector<Ray> rays;
  for (int i = 0; i < 90; ++i) {
    const double a = 0.01 * i;
    rays.push_back({{6.3 + 0.3 * std::cos(3 * a), 6.3 + 0.3 * std::sin(5 * a)}, true});
  }
  grid.insert({5.0, 5.0}, rays, kUpdate, 100.0);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(6.0, 6.7);
  const double h = 1e-4;
  int checked = 0;
  for (int k = 0; k < 300; ++k) {
    const Eigen::Vector2d p(u(rng), u(rng));
    // Skip points within h of a centre line, where the bilinear gradient jumps.
    const Eigen::Vector2d c = p / 0.1 - Eigen::Vector2d(0.5, 0.5);
    if (std::abs(c.x() - std::round(c.x())) < 0.01 || std::abs(c.y() - std::round(c.y())) < 0.01) continue;
    const OccupancyGrid::Sample s = grid.sample(p);
    const double gx = (grid.sample(p + Eigen::Vector2d(h, 0)).value - grid.sample(p - Eigen::Vector2d(h, 0)).value) / (2 * h);
    const double gy = (grid.sample(p + Eigen::Vector2d(0, h)).value - grid.sample(p - Eigen::Vector2d(0, h)).value) / (2 * h);
    EXPECT_NEAR(s.gradient_per_m.x(), gx, 2e-2) << p.transpose();
    EXPECT_NEAR(s.gradient_per_m.y(), gy, 2e-2) << p.transpose();
    ++checked;
  }
  EXPECT_GT(checked, 200);
}

TEST(OccupancyGrid, RejectsABadResolution) {
  EXPECT_THROW(OccupancyGrid(0.0), std::invalid_argument);
  EXPECT_THROW(OccupancyGrid(-1.0), std::invalid_argument);
  EXPECT_THROW(OccupancyGrid(std::nan("")), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::slam2d
