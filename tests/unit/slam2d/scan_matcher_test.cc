#include "slam2d/scan_matcher.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "sim_scans.h"

namespace rmap::slam2d {
namespace {

/// Endpoints of a scan in the base frame (identity mount), finite beams only.
std::vector<MatchPoint> endpoints(const LaserScan& scan) {
  std::vector<MatchPoint> points;
  for (size_t i = 0; i < scan.ranges_m.size(); ++i)
    if (std::isfinite(scan.ranges_m[i]) && scan.ranges_m[i] < scan.range_max_m)
      points.push_back({{scan.ranges_m[i] * std::cos(scan.angles_rad[i]), scan.ranges_m[i] * std::sin(scan.angles_rad[i])}});
  return points;
}

void insertAt(GridMap2d& map, const Pose2& pose, const std::vector<MatchPoint>& points,
              const OccupancyUpdate& update = {}) {
  std::vector<Ray> rays;
  for (const MatchPoint& p : points) rays.push_back({pose * p.p_m, true});
  map.insert(pose.translation(), rays, update, 100.0);
}

class SimulatedRoom : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { world_ = new sim::VoxelWorld(testing::simBuilding()); }
  static void TearDownTestSuite() { delete world_; }
  static sim::VoxelWorld* world_;
};
sim::VoxelWorld* SimulatedRoom::world_ = nullptr;

TEST_F(SimulatedRoom, RecoversAKnownOffset) {
  const Pose2 truth = testing::simTour(*world_, 1, 0.3).front();
  std::mt19937_64 rng(11);
  const sim::Laser2dModel model = sim::Laser2dModel::sickLike();
  GridMap2d map(0.05, 3);
  // Three scans into the map, then a fresh scan (new noise) to match.
  for (int k = 0; k < 3; ++k) insertAt(map, truth, endpoints(testing::simScan(*world_, truth, model, rng)));
  const std::vector<MatchPoint> scan = endpoints(testing::simScan(*world_, truth, model, rng));
  ASSERT_GT(scan.size(), 100u);
  const Pose2 offsets[] = {{0.15, -0.10, 0.05}, {-0.2, 0.05, -0.08}, {0.0, 0.25, 0.0}};
  for (const Pose2& offset : offsets) {
    const Pose2 start = truth * offset;
    const MatchResult r = matchScan(map, scan, start, std::nullopt, ScanMatcherOptions{});
    EXPECT_NEAR(r.pose.x_m, truth.x_m, 0.02) << offset.x_m << " " << offset.y_m;
    EXPECT_NEAR(r.pose.y_m, truth.y_m, 0.02);
    EXPECT_NEAR(normalizeAngle(r.pose.theta_rad - truth.theta_rad), 0.0, 0.005);
    EXPECT_LT(r.mean_residual, 0.5);
    EXPECT_GT(r.hessian.trace(), 0.0);
  }
}

TEST_F(SimulatedRoom, TheCorrelativeSearchCatchesALargeTurn) {
  const Pose2 truth = testing::simTour(*world_, 1, 0.3).front();
  std::mt19937_64 rng(12);
  const sim::Laser2dModel model = sim::Laser2dModel::sickLike();
  GridMap2d map(0.05, 3);
  insertAt(map, truth, endpoints(testing::simScan(*world_, truth, model, rng)));
  const std::vector<MatchPoint> scan = endpoints(testing::simScan(*world_, truth, model, rng));
  const Pose2 start = truth * Pose2{0.25, -0.2, 0.6};
  ScanMatcherOptions options;
  const Pose2 plain = matchScan(map, scan, start, std::nullopt, options).pose;
  EXPECT_GT(std::abs(normalizeAngle(plain.theta_rad - truth.theta_rad)), 0.1) << "Gauss–Newton alone cannot turn this far";
  options.search_rad = 0.8;
  options.search_m = 0.4;
  const Pose2 searched = matchScan(map, scan, start, std::nullopt, options).pose;
  EXPECT_NEAR(searched.x_m, truth.x_m, 0.02);
  EXPECT_NEAR(searched.y_m, truth.y_m, 0.02);
  EXPECT_NEAR(normalizeAngle(searched.theta_rad - truth.theta_rad), 0.0, 0.005);
}

/// Points every 5 cm along two walls parallel to x, at y = left_m and y = right_m, from x = from_m to to_m.
std::vector<MatchPoint> corridorWalls(double from_m, double to_m, double left_m, double right_m) {
  std::vector<MatchPoint> walls;
  for (double x = from_m; x <= to_m; x += 0.05) {
    walls.push_back({{x, left_m}});
    walls.push_back({{x, right_m}});
  }
  return walls;
}

/// A map of corridorWalls(from_m, to_m, ±1.025) (through the cell centres), seen three times from the origin.
GridMap2d corridorMap(double from_m, double to_m) {
  GridMap2d map(0.05, 3);
  const std::vector<MatchPoint> walls = corridorWalls(from_m, to_m, 1.025, -1.025);
  for (int k = 0; k < 3; ++k) insertAt(map, Pose2{}, walls);
  return map;
}

TEST(ScanMatcher, ACorridorLeavesItsAxisAtTheInitialGuess) {
  // Two long walls: x is unobservable.
  const GridMap2d map = corridorMap(-8.0, 8.0);
  const std::vector<MatchPoint> scan = corridorWalls(-4.0, 4.0, 0.955, -1.095);  // 7 cm off the centre line
  const Pose2 start{0.3, 0.0, 0.0};
  const MatchResult r = matchScan(map, scan, start, std::nullopt, ScanMatcherOptions{});
  EXPECT_NEAR(r.pose.y_m, 0.07, 0.01);
  EXPECT_NEAR(r.pose.theta_rad, 0.0, 0.005);
  EXPECT_NEAR(r.pose.x_m, start.x_m, 0.05) << "the corridor axis must not run away";
  // The Hessian says so: x has (almost) no information.
  EXPECT_LT(r.hessian(0, 0), 1e-2 * r.hessian(1, 1));
  // A prior on the axis holds it where the prior says.
  const PosePrior prior{{0.2, 0.0, 0.0}, {50.0, 0.0, 0.0}};
  EXPECT_NEAR(matchScan(map, scan, start, prior, ScanMatcherOptions{}).pose.x_m, 0.2, 0.02);
}

TEST(ScanMatcher, ATranslationWeightKeepsTheSearchFromSlidingAlongACorridor) {
  // The map's walls end at x = 4 m; the scan, taken at x = 0, sees them on to
  // 4.3 m (new ground). A pose 0.2 m back puts those points on mapped wall: the
  // search's coarse score (Σ M, unknown = 0) rises by more than the 2 % the
  // guess is given, though the guess is right.
  const GridMap2d map = corridorMap(-8.0, 4.0);
  const std::vector<MatchPoint> scan = corridorWalls(-2.0, 4.3, 1.025, -1.025);
  ScanMatcherOptions options;
  options.search_rad = options.search_step_rad;
  options.search_m = 0.2;
  options.coarse_iterations = options.fine_iterations = 0;  // the search's pick alone
  const Pose2 guess{0.0, 0.0, 0.0};
  EXPECT_LT(matchScan(map, scan, guess, std::nullopt, options).pose.x_m, -0.1) << "unweighed, the search slides back";
  options.search_translation_weight = 2.0;  // a 0.2 m shift costs 8 % of its score
  EXPECT_NEAR(matchScan(map, scan, guess, std::nullopt, options).pose.x_m, 0.0, 0.05);
}

TEST(ScanMatcher, ThePriorHoldsAlongACorridorPastTheMapsEnd) {
  // The map's walls end at x = 4 m; the scan, taken at x = 0 where the
  // odometry's prior says, sees them on to 4.3 m. The endpoints past the
  // edge pull the scan back along the axis, which the data leaves flat.
  const GridMap2d map = corridorMap(-8.0, 4.0);
  const std::vector<MatchPoint> scan = corridorWalls(-2.0, 4.3, 1.025, -1.025);
  const Pose2 truth{0.0, 0.0, 0.0};
  const PosePrior prior{truth, {0.05, 0.05, 0.0}};  // Slam2dOptions' fixed odometry information
  ScanMatcherOptions options;
  const MatchResult held = matchScan(map, scan, truth, prior, options);
  options.flat_information_cells = 0.0;
  const MatchResult slid = matchScan(map, scan, truth, prior, options);
  EXPECT_LT(slid.pose.x_m, -0.2) << "without the flat-direction prior the scan slides back";
  EXPECT_NEAR(held.pose.x_m, truth.x_m, 0.05);
  EXPECT_NEAR(held.pose.y_m, truth.y_m, 0.01);
  // Across the corridor the data still rules: odometry 0.15 m off sideways is corrected.
  const Pose2 sideways{0.0, 0.15, 0.0};
  const Pose2 corrected =
      matchScan(map, scan, sideways, PosePrior{sideways, prior.information}, ScanMatcherOptions{}).pose;
  EXPECT_NEAR(corrected.y_m, truth.y_m, 0.01);
  EXPECT_NEAR(corrected.x_m, truth.x_m, 0.05);
}

TEST(ScanMatcher, ARotationWeightKeepsTheSearchFromTurningOntoALookAlike) {
  // The map holds the scan's walls at the right heading only up to x = 1 m
  // (new ground beyond), and all of them turned by 0.4 rad (a look-alike
  // elsewhere in the map): the turned pose scores higher.
  const std::vector<MatchPoint> scan = corridorWalls(-2.0, 4.0, 1.025, -1.025);
  std::vector<MatchPoint> seen;
  for (const MatchPoint& p : scan)
    if (p.p_m.x() < 1.0) seen.push_back(p);
  GridMap2d map(0.05, 3);
  for (int k = 0; k < 3; ++k) {
    insertAt(map, Pose2{}, seen);
    insertAt(map, Pose2{0.0, 0.0, 0.4}, scan);
  }
  ScanMatcherOptions options;
  options.search_rad = 0.8;
  options.coarse_iterations = options.fine_iterations = 0;  // the search's pick alone
  const Pose2 guess{0.0, 0.0, 0.0};
  EXPECT_NEAR(matchScan(map, scan, guess, std::nullopt, options).pose.theta_rad, 0.4, 0.03)
      << "unweighed, the search turns onto the look-alike";
  options.search_rotation_weight = 20.0;  // a 0.4 rad turn keeps 4 % of its score, 2° keeps 98 %
  // Near the guess: the coarsest level (0.2 m cells) barely tells 3° apart at these ranges.
  EXPECT_NEAR(matchScan(map, scan, guess, std::nullopt, options).pose.theta_rad, 0.0, 0.06);
}

TEST(ScanMatcher, AWallSeenOnceFromAfarPullsTheScanBackUnlessReadAboveAFloor) {
  // A corridor's end wall 6 m ahead, mapped from one scan (range noise 2 cm),
  // then scanned again 1 m closer. The cells its rays crossed once hold
  // little free evidence (p = 0.40) while the unknown cells behind the wall
  // read 0: the map rises in front of the wall, and Gauss–Newton pulls the
  // new endpoints toward the observer (the step comes out short).
  const auto mean_step_error_m = [](float value_floor_probability) {
    std::mt19937_64 rng(21);
    std::normal_distribution<double> noise_m(0.0, 0.02);
    const auto scanFrom = [&](double x_m) {
      std::vector<MatchPoint> scan = corridorWalls(-x_m, 6.0 - x_m, 1.025, -1.025);
      for (double y = -1.0; y <= 1.0; y += 0.02) {
        const Eigen::Vector2d end(6.0 - x_m, y);
        scan.push_back({end * (1.0 + noise_m(rng) / end.norm())});
      }
      return scan;
    };
    OccupancyUpdate update;
    update.value_floor_probability = value_floor_probability;
    double sum_m = 0.0;
    const int trials = 20;
    for (int k = 0; k < trials; ++k) {
      GridMap2d map(0.05, 3);
      insertAt(map, Pose2{}, scanFrom(0.0), update);
      const Pose2 truth{1.0, 0.0, 0.0};
      sum_m += matchScan(map, scanFrom(1.0), truth, std::nullopt, ScanMatcherOptions{}).pose.x_m - truth.x_m;
    }
    return sum_m / trials;
  };
  const double read_as_p_m = mean_step_error_m(0.0f);
  EXPECT_LT(read_as_p_m, -0.008) << "read as p, the scan is pulled back";
  // Above a floor of 0.3 the crossed cells read (almost) as the unknown ones.
  EXPECT_LT(std::abs(mean_step_error_m(0.3f)), 0.2 * std::abs(read_as_p_m));
}

TEST(ScanMatcher, ReturnsTheInitialGuessWithNothingToMatch) {
  GridMap2d empty(0.05, 3);
  const std::vector<MatchPoint> scan{{{1.0, 0.0}}, {{0.0, 1.0}}};
  const Pose2 start{1.0, 2.0, 0.3};
  Pose2 r = matchScan(empty, scan, start, std::nullopt, ScanMatcherOptions{}).pose;
  EXPECT_EQ(r.x_m, start.x_m);
  EXPECT_EQ(r.theta_rad, start.theta_rad);
  GridMap2d map(0.05, 3);
  insertAt(map, Pose2{}, scan);
  // Endpoints far from anything mapped: no gradient, no step.
  const std::vector<MatchPoint> far{{{100.0, 0.0}}};
  r = matchScan(map, far, start, std::nullopt, ScanMatcherOptions{}).pose;
  EXPECT_TRUE(r.isFinite());
  EXPECT_NEAR(r.x_m, start.x_m, 1e-12);
  EXPECT_NEAR(r.y_m, start.y_m, 1e-12);
  EXPECT_TRUE(matchScan(map, {}, start, std::nullopt, ScanMatcherOptions{}).pose.isFinite());
}

}  // namespace
}  // namespace rmap::slam2d
