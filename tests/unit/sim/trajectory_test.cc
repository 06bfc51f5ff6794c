#include "sim/trajectory.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "sim/building.h"
#include "sim/bt_world.h"

namespace rmap::sim {
namespace {

using Eigen::Vector3d;
using Eigen::Vector3i;

/// Distance from a point to the nearest occupied voxel, searched within `radius` (else +inf).
double clearance(const VoxelWorld& w, const Vector3d& p, double radius) {
  const double v = w.voxelSize();
  double best = INFINITY;
  const Vector3i lo = ((p.array() - radius) / v).floor().cast<int>(), hi = ((p.array() + radius) / v).floor().cast<int>();
  for (int z = lo.z(); z <= hi.z(); ++z) {
    for (int y = lo.y(); y <= hi.y(); ++y) {
      for (int x = lo.x(); x <= hi.x(); ++x) {
        if (!w.occupiedVoxel(Vector3i(x, y, z))) continue;
        const Vector3d box_lo = Vector3d(x, y, z) * v, box_hi = box_lo + Vector3d::Constant(v);
        best = std::min(best, (p.cwiseMax(box_lo).cwiseMin(box_hi) - p).norm());
      }
    }
  }
  return best;
}

BuildingOptions fastBuilding(int floors = 1) {
  BuildingOptions o;
  o.voxel_m = 0.05;
  o.floors = floors;
  return o;
}

/// Checks what every tour must satisfy.
void expectValidTour(const VoxelWorld& w, const std::vector<Eigen::Isometry3d>& poses, const TrajectoryOptions& o) {
  ASSERT_EQ(poses.size(), static_cast<size_t>(o.num_poses));
  for (size_t i = 0; i < poses.size(); ++i) {
    const Vector3d p = poses[i].translation();
    ASSERT_FALSE(w.occupied(p)) << "pose " << i;
    ASSERT_GE(clearance(w, p, o.clearance_m + 0.1), o.clearance_m - 1e-9) << "pose " << i;
    if (w.hasKnownFree()) {
      ASSERT_TRUE(w.knownFree(p)) << "pose " << i;
    }
    // Level, at sensor height above the surface below.
    ASSERT_TRUE(poses[i].linear().col(2).isApprox(Vector3d::UnitZ(), 1e-12));
    const auto down = w.castRay(p, -Vector3d::UnitZ(), 10.0);
    ASSERT_TRUE(down) << "pose " << i;
    ASSERT_NEAR(down->range_m, o.sensor_height_m, o.max_step_m + 1e-9) << "pose " << i;
    if (i + 1 == poses.size()) continue;
    const Vector3d move = poses[i + 1].translation() - p;
    ASSERT_LE(move.norm(), o.step_m + 1e-9) << "pose " << i;
    ASSERT_GT(move.norm(), 0.0) << "pose " << i;
    if (move.head<2>().norm() > 1e-6) {  // heading along the horizontal direction of travel
      ASSERT_GT(poses[i].linear().col(0).head<2>().dot(move.head<2>().normalized()), 1.0 - 1e-9) << "pose " << i;
    }
  }
}

TEST(Trajectory, ToursABuildingThroughFreeSpace) {
  const VoxelWorld w = makeBuilding(fastBuilding(), 1);
  TrajectoryOptions o;
  o.num_poses = 400;
  const auto poses = planTrajectory(w, o, 1);
  expectValidTour(w, poses, o);
  for (const auto& pose : poses) EXPECT_NEAR(pose.translation().z(), 1.0, 1e-9);  // flat single storey

  // Steps are the configured length except where the path steps up or down.
  int full_steps = 0;
  for (size_t i = 0; i + 1 < poses.size(); ++i) {
    full_steps += (poses[i + 1].translation() - poses[i].translation()).norm() > o.step_m - 1e-4;
  }
  EXPECT_EQ(full_steps, o.num_poses - 1);

  // Coverage: share of the reachable floor within 3 m of some pose, and the spread of the tour.
  const NavigableSpace space(w, o);
  size_t reachable = 0, covered = 0;
  for (size_t i = 0; i < space.size(); ++i) {
    if (space.component(static_cast<int>(i)) != 0) continue;
    ++reachable;
    const Vector3d s = space.sensorPosition(static_cast<int>(i));
    for (const auto& pose : poses) {
      if ((pose.translation() - s).head<2>().norm() < 3.0) {
        ++covered;
        break;
      }
    }
  }
  Eigen::AlignedBox3d spread;
  for (const auto& pose : poses) spread.extend(pose.translation());
  const double share = static_cast<double>(covered) / reachable;
  std::printf("[ tour ] %d poses cover %.0f %% of %zu reachable cells; spread %.1f x %.1f m\n", o.num_poses,
              100 * share, reachable, spread.sizes().x(), spread.sizes().y());
  EXPECT_GT(share, 0.7);  // 0.74–0.94 over building seeds 1–12
  EXPECT_GT(spread.sizes().x(), 0.8 * 24.0);
  EXPECT_GT(spread.sizes().y(), 0.75 * 16.0);
}

TEST(Trajectory, ClimbsToTheUpperStorey) {
  const VoxelWorld w = makeBuilding(fastBuilding(2), 5);
  TrajectoryOptions o;
  o.num_poses = 800;
  const auto poses = planTrajectory(w, o, 5);
  expectValidTour(w, poses, o);
  int ground = 0, upper = 0;
  for (const auto& pose : poses) {
    ground += std::abs(pose.translation().z() - 1.0) < 1e-6;
    upper += std::abs(pose.translation().z() - 4.0) < 1e-6;
  }
  std::printf("[ tour ] %d poses on the ground storey, %d upstairs, %d on the stairs\n", ground, upper,
              o.num_poses - ground - upper);
  EXPECT_GT(ground, 50);
  EXPECT_GT(upper, 50);
}

TEST(Trajectory, StaysInKnownFreeSpaceOfAMapWorld) {
  // A 6 m × 6 m room at 0.1 m whose tree saw only x < 4 m as free.
  map3d::BtTree tree;
  tree.resolution_m = 0.1;
  for (int y = 0; y < 60; ++y) {
    for (int x = 0; x < 60; ++x) {
      tree.leaves.push_back({{x, y, -1}, 1, true});  // floor
      const bool wall = x == 0 || y == 0 || x == 59 || y == 59;
      for (int z = 0; z < 30; ++z) {
        if (wall) {
          tree.leaves.push_back({{x, y, z}, 1, true});
        } else if (x < 40) {
          tree.leaves.push_back({{x, y, z}, 1, false});
        }
      }
    }
  }
  const VoxelWorld w = worldFromBt(tree, 0.5f, 3);
  TrajectoryOptions o;
  o.num_poses = 150;
  const auto poses = planTrajectory(w, o, 3);
  expectValidTour(w, poses, o);
  for (const auto& pose : poses) EXPECT_LT(pose.translation().x(), 4.0);
}

TEST(Trajectory, DeterministicGivenASeed) {
  const VoxelWorld w = makeBuilding(fastBuilding(), 2);
  TrajectoryOptions o;
  o.num_poses = 120;
  const auto a = planTrajectory(w, o, 8), b = planTrajectory(w, o, 8), c = planTrajectory(w, o, 9);
  for (size_t i = 0; i < a.size(); ++i) ASSERT_TRUE(a[i].isApprox(b[i], 0.0)) << i;
  EXPECT_FALSE(a[0].isApprox(c[0]));
}

TEST(Trajectory, ReportsMissingNavigableSpaceAndBadOptions) {
  VoxelWorld empty = VoxelWorld::covering(Eigen::AlignedBox3d(Vector3d::Zero(), Vector3d::Constant(4)), 0.05);
  EXPECT_THROW(planTrajectory(empty, TrajectoryOptions{}, 1), std::runtime_error);
  try {
    planTrajectory(empty, TrajectoryOptions{}, 1);
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no navigable space"), std::string::npos);
  }
  const VoxelWorld w = makeBuilding(fastBuilding(), 1);
  TrajectoryOptions o;
  o.num_poses = 0;
  EXPECT_THROW(planTrajectory(w, o, 1), std::invalid_argument);
  o = TrajectoryOptions{};
  o.step_m = 0.2;  // below max_step_m
  EXPECT_THROW(planTrajectory(w, o, 1), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::sim
