#include "slam2d/correlative_matcher.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

#include "sim_scans.h"

namespace rmap::slam2d {
namespace {

/// Score of lattice pose (k, i, j) exactly as correlative_matcher.h defines it.
double latticeScore(const ProbabilityRaster& raster, std::span<const Eigen::Vector2d> points, const Pose2& center,
                    double theta_rad, int i, int j) {
  const Pose2 rotated{center.x_m, center.y_m, theta_rad};
  double sum = 0.0;
  for (const Eigen::Vector2d& p : points) {
    const Eigen::Vector2i c = raster.cellOf(rotated * p);
    sum += raster.at(c.x() + i, c.y() + j);
  }
  return sum / static_cast<double>(points.size());
}

/// Best score over the whole lattice, by enumeration.
double bruteForceBest(const CorrelativeMatcher& matcher, std::span<const Eigen::Vector2d> points, const Pose2& center,
                      double window_m, double window_rad) {
  const SearchLattice lattice = matcher.lattice(points, window_m, window_rad);
  double best = -1.0;
  for (int k = -lattice.angular_steps; k <= lattice.angular_steps; ++k)
    for (int j = -lattice.linear_steps; j <= lattice.linear_steps; ++j)
      for (int i = -lattice.linear_steps; i <= lattice.linear_steps; ++i)
        best = std::max(best, latticeScore(matcher.raster(), points, center,
                                           center.theta_rad + k * lattice.angular_step_rad, i, j));
  return best;
}

ProbabilityRaster randomRaster(std::mt19937_64& rng, int width, int height) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  ProbabilityRaster raster;
  raster.origin_m = {-0.7, 0.3};
  raster.resolution_m = 0.1;
  raster.width = width;
  raster.height = height;
  raster.outside_p = 0.5f * u(rng);
  for (int n = 0; n < width * height; ++n) raster.p.push_back(u(rng) * u(rng));  // mostly low, a few high
  return raster;
}

/// A square room with walls 0.05 m thick at ±half_m, robot frame points of a
/// 360-beam scan from `robot` (exact ranges, no noise).
std::vector<Eigen::Vector2d> roomScan(const Pose2& robot, double half_m, int beams) {
  std::vector<Eigen::Vector2d> points;
  const Pose2 inv = robot.inverse();
  for (int b = 0; b < beams; ++b) {
    const double a = robot.theta_rad + 2.0 * std::numbers::pi * b / beams;
    const Eigen::Vector2d d(std::cos(a), std::sin(a));
    double t = INFINITY;
    for (int axis = 0; axis < 2; ++axis)
      if (d[axis] != 0.0) {
        const double o = axis == 0 ? robot.x_m : robot.y_m;
        t = std::min(t, ((d[axis] > 0 ? half_m : -half_m) - o) / d[axis]);
      }
    points.push_back(inv * (robot.translation() + t * d));
  }
  return points;
}

/// The room's walls rasterised from one scan at the origin.
ProbabilityRaster roomRaster(double half_m) {
  const std::vector<Eigen::Vector2d> scan = roomScan(Pose2{}, half_m, 720);
  const PosedScan posed{Pose2{}, scan};
  return rasterFromScans(std::span(&posed, 1), 0.05, 0.1f, OccupancyUpdate{}, 100.0, 4);
}

TEST(CorrelativeMatcher, EqualsBruteForceOnRandomRasters) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 12; ++trial) {
    const ProbabilityRaster raster = randomRaster(rng, 37 + trial, 29);
    std::vector<Eigen::Vector2d> points;
    for (int n = 0; n < 20 + trial; ++n) points.push_back({1.6 * u(rng), 1.6 * u(rng)});
    // With a fixed angular step (else they would make it fine and the brute
    // force slow): a few points off the raster at every shift (they score
    // outside_p whatever the pose).
    // Others 8.5 m out: beyond the levels' padding for some rotations, not off the raster.
    if (trial % 2 == 1) {
      for (int n = 0; n < 3; ++n) points.push_back({5.0 * u(rng) + (u(rng) > 0 ? 20.0 : -20.0), 4.0 * u(rng)});
      for (int n = 0; n < 3; ++n) {
        const double a = std::numbers::pi * u(rng);
        points.push_back({8.5 * std::cos(a), 8.5 * std::sin(a)});
      }
    }
    const Pose2 center{1.2 + 0.5 * u(rng), 1.5 + 0.5 * u(rng), std::numbers::pi * u(rng)};
    // Every fourth a full turn: enough rotations for the matcher to bound groups of them.
    const double window_m = 0.45 + 0.2 * (trial % 4), window_rad = trial % 4 == 3 ? std::numbers::pi : 0.3 * (trial % 3);
    CorrelativeMatcherOptions options;
    options.angular_step_rad = trial % 2 == 0 ? 0.0 : 0.07;
    // The lattice depends on the step only, so one enumeration serves every level count.
    const double expected = bruteForceBest(CorrelativeMatcher(raster, options), points, center, window_m, window_rad);
    // fast_window_m 0: most points take the checked path; 5 m: all do not.
    for (const auto& [levels, fast_window_m] : {std::pair{1, 5.0}, {2, 5.0}, {3, 0.0}, {3, 5.0}, {7, 0.0}, {7, 5.0}}) {
      options.branch_levels = levels;
      options.fast_window_m = fast_window_m;
      const CorrelativeMatcher matcher(raster, options);
      const std::optional<CorrelativeMatch> m = matcher.match(points, center, window_m, window_rad, 0.0);
      ASSERT_TRUE(m) << "trial " << trial << " levels " << levels << " fast " << fast_window_m;
      EXPECT_EQ(m->score, expected) << "trial " << trial << " levels " << levels << " fast " << fast_window_m;
      // The pose is on the lattice and scores what the match says.
      const double r = raster.resolution_m;
      const int i = static_cast<int>(std::lround((m->pose.x_m - center.x_m) / r));
      const int j = static_cast<int>(std::lround((m->pose.y_m - center.y_m) / r));
      const SearchLattice lattice = matcher.lattice(points, window_m, window_rad);
      const double k_real = normalizeAngle(m->pose.theta_rad - center.theta_rad) / lattice.angular_step_rad;
      const int k = static_cast<int>(std::lround(k_real));
      EXPECT_NEAR(k_real, k, 1e-6);
      EXPECT_LE(std::abs(i), lattice.linear_steps);
      EXPECT_LE(std::abs(j), lattice.linear_steps);
      EXPECT_LE(std::abs(k), lattice.angular_steps);
      EXPECT_NEAR(latticeScore(raster, points, center, center.theta_rad + k * lattice.angular_step_rad, i, j),
                  m->score, 1e-12);
    }
  }
}

TEST(CorrelativeMatcher, AnExcludedDiskEqualsBruteForceOutsideIt) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 6; ++trial) {
    const ProbabilityRaster raster = randomRaster(rng, 41, 33);
    std::vector<Eigen::Vector2d> points;
    for (int n = 0; n < 25; ++n) points.push_back({1.6 * u(rng), 1.6 * u(rng)});
    const Pose2 center{1.3 + 0.3 * u(rng), 1.4 + 0.3 * u(rng), std::numbers::pi * u(rng)};
    const double window_m = 0.65, window_rad = 0.2;
    CorrelativeMatcherOptions options;
    options.angular_step_rad = 0.07;
    // The disk around the unrestricted best, so the answer must change.
    const std::optional<CorrelativeMatch> best = CorrelativeMatcher(raster, options).match(points, center, window_m, window_rad, 0.0);
    ASSERT_TRUE(best);
    const ExcludedDisk disk{best->pose.translation() + Eigen::Vector2d(0.03 * u(rng), 0.03 * u(rng)), 0.1 + 0.1 * trial};
    const SearchLattice lattice = CorrelativeMatcher(raster, options).lattice(points, window_m, window_rad);
    double expected = -1.0;
    for (int k = -lattice.angular_steps; k <= lattice.angular_steps; ++k)
      for (int j = -lattice.linear_steps; j <= lattice.linear_steps; ++j)
        for (int i = -lattice.linear_steps; i <= lattice.linear_steps; ++i) {
          const Eigen::Vector2d t(center.x_m + i * raster.resolution_m, center.y_m + j * raster.resolution_m);
          if ((t - disk.center_m).norm() <= disk.radius_m) continue;
          expected = std::max(expected, latticeScore(raster, points, center,
                                                     center.theta_rad + k * lattice.angular_step_rad, i, j));
        }
    for (int levels : {1, 2, 4, 7}) {
      options.branch_levels = levels;
      const std::optional<CorrelativeMatch> m =
          CorrelativeMatcher(raster, options).match(points, center, window_m, window_rad, 0.0, disk);
      ASSERT_TRUE(m) << "trial " << trial << " levels " << levels;
      EXPECT_NEAR(m->score, expected, 1e-12) << "trial " << trial << " levels " << levels;
      EXPECT_GT((m->pose.translation() - disk.center_m).norm(), disk.radius_m - 1e-9);
      EXPECT_LT(m->score, best->score + 1e-12);
      // The first pose reaching a score: outside the disk, reaching it, and none above the best outside.
      const CorrelativeMatcher matcher(raster, options);
      const std::optional<CorrelativeMatch> first =
          matcher.firstAtLeast(points, center, window_m, window_rad, expected - 0.05, disk);
      ASSERT_TRUE(first);
      EXPECT_GE(first->score, expected - 0.05);
      EXPECT_GT((first->pose.translation() - disk.center_m).norm(), disk.radius_m - 1e-9);
      EXPECT_TRUE(matcher.firstAtLeast(points, center, window_m, window_rad, expected, disk));
      EXPECT_FALSE(matcher.firstAtLeast(points, center, window_m, window_rad, std::nextafter(expected, 2.0), disk));
    }
  }
  const CorrelativeMatcher matcher(randomRaster(rng, 20, 20));
  const std::vector<Eigen::Vector2d> one{{0.5, 0.5}};
  EXPECT_THROW(matcher.match(one, Pose2{1, 1, 0}, 0.3, 0.0, 0.0, ExcludedDisk{{1.0, 1.0}, -0.1}), std::invalid_argument);
  EXPECT_THROW(matcher.match(one, Pose2{1, 1, 0}, 0.3, 0.0, 0.0, ExcludedDisk{{NAN, 1.0}, 0.1}), std::invalid_argument);
  // A disk over the whole window leaves nothing.
  EXPECT_FALSE(matcher.match(one, Pose2{1, 1, 0}, 0.3, 0.0, 0.0, ExcludedDisk{{1.0, 1.0}, 1.0}));
}

TEST(CorrelativeMatcher, RespectsMinScore) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const CorrelativeMatcher matcher(randomRaster(rng, 50, 40));
  std::vector<Eigen::Vector2d> points;
  for (int n = 0; n < 30; ++n) points.push_back({1.5 * u(rng), 1.5 * u(rng)});
  const Pose2 center{2.4, 2.1, 0.2};
  const double best = bruteForceBest(matcher, points, center, 0.8, 0.4);
  const std::optional<CorrelativeMatch> at = matcher.match(points, center, 0.8, 0.4, best);
  ASSERT_TRUE(at);
  EXPECT_EQ(at->score, best);
  EXPECT_FALSE(matcher.match(points, center, 0.8, 0.4, std::nextafter(best, 2.0)));
  EXPECT_FALSE(matcher.match(points, center, 0.8, 0.4, 1.0));
}

TEST(CorrelativeMatcher, FindsAKnownOffsetInASyntheticRoom) {
  const double half_m = 4.025;  // walls through cell centres
  const CorrelativeMatcher matcher(roomRaster(half_m));
  // An asymmetric box would be needed for a unique heading; a square room has
  // four, so the offset stays within ±π/4 of the truth and the window below.
  const Pose2 truth{0.83, -1.27, 0.31};
  const std::vector<Eigen::Vector2d> scan = roomScan(truth, half_m, 360);
  const Pose2 center = truth * Pose2{-0.42, 0.36, -0.28};
  const std::optional<CorrelativeMatch> m = matcher.match(scan, center, 1.0, 0.5, 0.5);
  ASSERT_TRUE(m);
  const SearchLattice lattice = matcher.lattice(scan, 1.0, 0.5);
  EXPECT_NEAR(m->pose.x_m, truth.x_m, 0.05);
  EXPECT_NEAR(m->pose.y_m, truth.y_m, 0.05);
  EXPECT_NEAR(normalizeAngle(m->pose.theta_rad - truth.theta_rad), 0.0, lattice.angular_step_rad);
  EXPECT_GT(m->score, 0.5);
}

class SimulatedBuilding : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { world_ = new sim::VoxelWorld(testing::simBuilding()); }
  static void TearDownTestSuite() { delete world_; }
  static sim::VoxelWorld* world_;
};
sim::VoxelWorld* SimulatedBuilding::world_ = nullptr;

/// Endpoints of the finite returns, robot frame (identity mount).
std::vector<Eigen::Vector2d> endpointsXy(const LaserScan& scan) {
  std::vector<Eigen::Vector2d> points;
  for (size_t i = 0; i < scan.ranges_m.size(); ++i)
    if (std::isfinite(scan.ranges_m[i]) && scan.ranges_m[i] < scan.range_max_m)
      points.emplace_back(scan.ranges_m[i] * std::cos(scan.angles_rad[i]), scan.ranges_m[i] * std::sin(scan.angles_rad[i]));
  return points;
}

TEST_F(SimulatedBuilding, RecoversARevisitOverAFullTurn) {
  // A submap from a few scans along a tour; a later scan from near the middle
  // of it, searched with no heading knowledge and a wide translation window.
  const std::vector<Pose2> tour = testing::simTour(*world_, 6, 0.4);
  sim::Laser2dModel model;
  model.fov_deg = 360.0;
  model.beams = 360;
  std::mt19937_64 rng(21);
  std::vector<std::vector<Eigen::Vector2d>> scans;
  std::vector<PosedScan> posed;
  for (const Pose2& p : tour) scans.push_back(endpointsXy(testing::simScan(*world_, p, model, rng)));
  for (size_t i = 0; i < tour.size(); ++i) posed.push_back({tour[i], scans[i]});
  const CorrelativeMatcher matcher(rasterFromScans(posed, 0.05, 0.1f));
  const Pose2 truth = tour[3];
  const std::vector<Eigen::Vector2d> query = endpointsXy(testing::simScan(*world_, truth, model, rng));
  ASSERT_GT(query.size(), 300u);
  const Pose2 center = truth * Pose2{1.3, -0.9, 2.4};
  const std::optional<CorrelativeMatch> m = matcher.match(query, center, 2.0, std::numbers::pi, 0.5);
  ASSERT_TRUE(m);
  const SearchLattice lattice = matcher.lattice(query, 2.0, std::numbers::pi);
  EXPECT_NEAR(m->pose.x_m, truth.x_m, 0.06);
  EXPECT_NEAR(m->pose.y_m, truth.y_m, 0.06);
  EXPECT_NEAR(normalizeAngle(m->pose.theta_rad - truth.theta_rad), 0.0, 2.0 * lattice.angular_step_rad);
  EXPECT_GT(m->score, 0.6);
}

TEST(CorrelativeMatcher, EmptyScanFindsNothing) {
  const CorrelativeMatcher matcher(roomRaster(2.025));
  EXPECT_FALSE(matcher.match({}, Pose2{}, 1.0, 0.5, 0.0));
  EXPECT_EQ(matcher.lattice({}, 1.0, 0.5).angular_steps, 0);
}

TEST(CorrelativeMatcher, RejectsBadWindowsAndOptions) {
  const CorrelativeMatcher matcher(roomRaster(2.025));
  const std::vector<Eigen::Vector2d> scan = roomScan(Pose2{}, 2.025, 90);
  EXPECT_THROW(matcher.match(scan, Pose2{}, -0.1, 0.5, 0.5), std::invalid_argument);
  EXPECT_THROW(matcher.match(scan, Pose2{}, NAN, 0.5, 0.5), std::invalid_argument);
  EXPECT_THROW(matcher.match(scan, Pose2{}, INFINITY, 0.5, 0.5), std::invalid_argument);
  EXPECT_THROW(matcher.match(scan, Pose2{}, 1e4, 0.5, 0.5), std::invalid_argument);
  EXPECT_THROW(matcher.match(scan, Pose2{}, 1.0, -0.1, 0.5), std::invalid_argument);
  EXPECT_THROW(matcher.match(scan, Pose2{}, 1.0, 3.2, 0.5), std::invalid_argument);
  EXPECT_THROW(matcher.match(scan, Pose2{}, 1.0, NAN, 0.5), std::invalid_argument);
  EXPECT_THROW(matcher.match(scan, Pose2{}, 1.0, 0.5, 1.1), std::invalid_argument);
  EXPECT_THROW(matcher.match(scan, Pose2{}, 1.0, 0.5, NAN), std::invalid_argument);
  EXPECT_THROW(matcher.match(scan, Pose2{NAN, 0.0, 0.0}, 1.0, 0.5, 0.5), std::invalid_argument);
  std::vector<Eigen::Vector2d> bad = scan;
  bad[3].x() = NAN;
  EXPECT_THROW(matcher.match(bad, Pose2{}, 1.0, 0.5, 0.5), std::invalid_argument);
  EXPECT_NO_THROW(matcher.match(scan, Pose2{}, 0.0, std::numbers::pi, 0.5));
  // A point 10 km away makes the extent-derived step 5 µrad: too many rotations.
  std::vector<Eigen::Vector2d> far = scan;
  far.push_back({1e4, 0.0});
  EXPECT_THROW(matcher.match(far, Pose2{}, 0.5, std::numbers::pi, 0.5), std::invalid_argument);

  CorrelativeMatcherOptions options;
  options.branch_levels = 0;
  EXPECT_THROW(CorrelativeMatcher(roomRaster(2.025), options), std::invalid_argument);
  options.branch_levels = 17;
  EXPECT_THROW(CorrelativeMatcher(roomRaster(2.025), options), std::invalid_argument);
  options = {};
  options.angular_step_rad = -0.01;
  EXPECT_THROW(CorrelativeMatcher(roomRaster(2.025), options), std::invalid_argument);
  options = {};
  options.fast_window_m = -1.0;
  EXPECT_THROW(CorrelativeMatcher(roomRaster(2.025), options), std::invalid_argument);
  ProbabilityRaster broken = roomRaster(2.025);
  broken.p.pop_back();
  EXPECT_THROW(CorrelativeMatcher{broken}, std::invalid_argument);
}

}  // namespace
}  // namespace rmap::slam2d
