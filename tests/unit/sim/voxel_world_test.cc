#include "sim/voxel_world.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

namespace rmap::sim {
namespace {

using Eigen::Vector3d;
using Eigen::Vector3i;

// Voxels of 1/8 m make every face and centre exactly representable.
constexpr double kV = 0.125;

/// Grid [−2, 2)³ with a wall x ∈ [1, 1.25).
VoxelWorld wallWorld() {
  VoxelWorld w(kV, Vector3i::Constant(-16), Vector3i::Constant(32));
  w.fillBox(box(1.0, -2, -2, 1.25, 2, 2), 0.5f);
  return w;
}

TEST(VoxelWorld, FillBoxSelectsVoxelsByCentre) {
  VoxelWorld w(kV, Vector3i::Constant(-16), Vector3i::Constant(32));
  w.fillBox(box(0, 0, 0, 1, 0.5, 0.25), 0.3f);
  EXPECT_EQ(w.occupiedCount(), 8u * 4u * 2u);
  EXPECT_TRUE(w.occupied(Vector3d(0.01, 0.01, 0.01)));
  EXPECT_TRUE(w.occupied(Vector3d(0.99, 0.49, 0.24)));
  EXPECT_FALSE(w.occupied(Vector3d(1.01, 0.2, 0.1)));
  EXPECT_FALSE(w.occupied(Vector3d(-0.01, 0.2, 0.1)));
  EXPECT_FALSE(w.occupied(Vector3d(0.5, 0.2, 0.26)));
  EXPECT_NEAR(w.reflectivityAt(Vector3d(0.5, 0.2, 0.1)), 0.3f, 1.0f / 255);
  EXPECT_EQ(w.reflectivityAt(Vector3d(1.5, 0.2, 0.1)), 0.0f);
  // Refilling counts nothing twice; clearing removes exactly what it covers.
  w.fillBox(box(0, 0, 0, 0.5, 0.5, 0.25), 0.9f);
  EXPECT_EQ(w.occupiedCount(), 64u);
  EXPECT_NEAR(w.reflectivityAt(Vector3d(0.1, 0.1, 0.1)), 0.9f, 1.0f / 255);
  w.clearBox(box(0, 0, 0, 0.25, 0.25, 0.25));
  EXPECT_EQ(w.occupiedCount(), 64u - 8u);
  EXPECT_FALSE(w.occupied(Vector3d(0.1, 0.1, 0.1)));
  EXPECT_GT(w.memoryBytes(), 0u);
}

TEST(VoxelWorld, OutsideTheGridIsFreeAndIgnored) {
  VoxelWorld w(kV, Vector3i(0, 0, 0), Vector3i(10, 10, 10));
  w.fillBox(box(-5, -5, -5, 5, 5, 5), 1.0f);  // clipped to the grid
  EXPECT_EQ(w.occupiedCount(), 1000u);
  EXPECT_FALSE(w.occupied(Vector3d(-0.01, 0.5, 0.5)));
  EXPECT_FALSE(w.occupied(Vector3d(1.25, 0.5, 0.5)));
  EXPECT_TRUE(w.occupied(Vector3d(1.2499, 0.5, 0.5)));
  EXPECT_FALSE(w.occupied(Vector3d(NAN, 0.5, 0.5)));
  EXPECT_EQ(w.bounds().min(), Vector3d::Zero());
  EXPECT_EQ(w.bounds().max(), Vector3d::Constant(1.25));
}

TEST(VoxelWorld, CoveringGridContainsTheBox) {
  const VoxelWorld w = VoxelWorld::covering(box(-0.3, 0.0, 1.0, 0.3, 2.0, 1.01), kV);
  EXPECT_EQ(w.minVoxel(), Vector3i(-3, 0, 8));
  EXPECT_EQ(w.dims(), Vector3i(6, 16, 1));
}

TEST(VoxelWorld, KnownFreeSpace) {
  VoxelWorld w(kV, Vector3i::Zero(), Vector3i(20, 20, 20));
  EXPECT_FALSE(w.hasKnownFree());
  EXPECT_FALSE(w.knownFree(Vector3d(0.5, 0.5, 0.5)));
  w.markKnownFree(VoxelBox(Vector3i(2, 2, 2), Vector3i(9, 10, 11)));
  EXPECT_TRUE(w.hasKnownFree());
  EXPECT_EQ(w.knownFreeCount(), 8u * 9u * 10u);
  EXPECT_TRUE(w.knownFreeVoxel(Vector3i(9, 10, 11)));
  EXPECT_FALSE(w.knownFreeVoxel(Vector3i(10, 10, 11)));
  EXPECT_TRUE(w.knownFree(w.voxelCenter(Vector3i(5, 5, 5))));
}

TEST(VoxelWorld, RejectsBadParameters) {
  EXPECT_THROW(VoxelWorld(0.0, Vector3i::Zero(), Vector3i::Ones()), std::invalid_argument);
  EXPECT_THROW(VoxelWorld(kV, Vector3i::Zero(), Vector3i(1, 0, 1)), std::invalid_argument);
  EXPECT_THROW(VoxelWorld(kV, Vector3i::Zero(), Vector3i::Constant(1 << 12)), std::invalid_argument);
  VoxelWorld w(kV, Vector3i::Zero(), Vector3i::Ones());
  EXPECT_THROW(w.fillBox(box(0, 0, 0, 1, 1, 1), 1.5f), std::invalid_argument);
  EXPECT_THROW(w.castRay(Vector3d::Zero(), Vector3d(1, 1, 0), 10.0), std::invalid_argument);
  EXPECT_THROW(w.castRay(Vector3d::Zero(), Vector3d::UnitX(), 0.0), std::invalid_argument);
  EXPECT_THROW(w.castRay(Vector3d(INFINITY, 0, 0), Vector3d::UnitX(), 1.0), std::invalid_argument);
}

TEST(VoxelWorldRay, DistanceAndNormalOfAWall) {
  const VoxelWorld w = wallWorld();
  const Vector3d origin(0.0625, 0.0625, 0.0625);
  auto hit = w.castRay(origin, Vector3d::UnitX(), 30.0);
  ASSERT_TRUE(hit);
  EXPECT_DOUBLE_EQ(hit->range_m, 1.0 - 0.0625);
  EXPECT_TRUE(hit->point_m.isApprox(Vector3d(1.0, 0.0625, 0.0625)));
  EXPECT_EQ(hit->normal, Vector3d(-1, 0, 0));
  EXPECT_NEAR(hit->reflectivity, 0.5f, 1.0f / 255);

  // From behind the wall, going −x: enters through the x = 1.25 face.
  hit = w.castRay(Vector3d(1.75, 0.3, -0.4), -Vector3d::UnitX(), 30.0);
  ASSERT_TRUE(hit);
  EXPECT_DOUBLE_EQ(hit->range_m, 0.5);
  EXPECT_EQ(hit->normal, Vector3d(1, 0, 0));

  // Oblique: the hit lies on the plane x = 1 at the analytic distance.
  const Vector3d dir = Vector3d(1.0, 0.5, -0.25).normalized();
  hit = w.castRay(origin, dir, 30.0);
  ASSERT_TRUE(hit);
  const double expected = (1.0 - origin.x()) / dir.x();
  EXPECT_NEAR(hit->range_m, expected, 1e-12);
  EXPECT_DOUBLE_EQ(hit->point_m.x(), 1.0);
  EXPECT_TRUE(hit->point_m.isApprox(origin + expected * dir, 1e-12));
  EXPECT_EQ(hit->normal, Vector3d(-1, 0, 0));

  // Away from the wall the ray leaves the grid without a hit.
  EXPECT_FALSE(w.castRay(origin, -Vector3d::UnitX(), 30.0));
}

TEST(VoxelWorldRay, HitsThroughVoxelEdgesAndCorners) {
  VoxelWorld w(kV, Vector3i::Constant(-16), Vector3i::Constant(32));
  w.fillVoxels(VoxelBox(Vector3i(4, 4, 0), Vector3i(4, 4, 0)), 1.0f);  // [0.5, 0.625)² × [0, 0.125)
  const double z = 0.0625;

  // Diagonal through the voxel's corner (0.5, 0.5): both side voxels are empty.
  auto hit = w.castRay(Vector3d(0.0625, 0.0625, z), Vector3d(1, 1, 0).normalized(), 10.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->range_m, std::sqrt(2.0) * 0.4375, 1e-12);
  EXPECT_TRUE(hit->point_m.isApprox(Vector3d(0.5, 0.5, z), 1e-12));
  EXPECT_TRUE(hit->normal == Vector3d(-1, 0, 0) || hit->normal == Vector3d(0, -1, 0));

  // Grazing along the voxel's lower y face: that face belongs to the voxel (half-open cells).
  hit = w.castRay(Vector3d(0.0625, 0.5, z), Vector3d::UnitX(), 10.0);
  ASSERT_TRUE(hit);
  EXPECT_DOUBLE_EQ(hit->range_m, 0.4375);
  // Grazing along its upper y face: the ray runs in the next row and misses.
  EXPECT_FALSE(w.castRay(Vector3d(0.0625, 0.625, z), Vector3d::UnitX(), 10.0));
  // Along its upper x face from above in y: the face belongs to the next column, a miss.
  EXPECT_FALSE(w.castRay(Vector3d(0.625, 1.5, z), -Vector3d::UnitY(), 10.0));
  hit = w.castRay(Vector3d(0.5, 1.5, z), -Vector3d::UnitY(), 10.0);
  ASSERT_TRUE(hit);
  EXPECT_DOUBLE_EQ(hit->range_m, 1.5 - 0.625);
  EXPECT_EQ(hit->normal, Vector3d(0, 1, 0));
}

TEST(VoxelWorldRay, EntersTheGridFromOutside) {
  const VoxelWorld w = wallWorld();
  // Straight in through the x = −2 face.
  auto hit = w.castRay(Vector3d(-5, 0.0625, 0.0625), Vector3d::UnitX(), 30.0);
  ASSERT_TRUE(hit);
  EXPECT_DOUBLE_EQ(hit->range_m, 6.0);
  EXPECT_EQ(hit->normal, Vector3d(-1, 0, 0));
  // Obliquely through the z = 2 face (from above the grid).
  const Vector3d origin(-1.5, 0.2, 2.5), dir = Vector3d(1.0, 0.0, -1.0).normalized();
  hit = w.castRay(origin, dir, 30.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->range_m, 2.5 * std::sqrt(2.0), 1e-12);
  EXPECT_EQ(hit->normal, Vector3d(-1, 0, 0));
  // An occupied voxel on the grid boundary is entered through the boundary face.
  VoxelWorld edge(kV, Vector3i::Constant(-16), Vector3i::Constant(32));
  edge.fillBox(box(-2, -2, -2, -1.875, 2, 2), 1.0f);
  hit = edge.castRay(Vector3d(-3, 0.1, 0.1), Vector3d::UnitX(), 30.0);
  ASSERT_TRUE(hit);
  EXPECT_DOUBLE_EQ(hit->range_m, 1.0);
  EXPECT_EQ(hit->normal, Vector3d(-1, 0, 0));
  // Rays that pass beside or turn away from the grid miss.
  EXPECT_FALSE(w.castRay(Vector3d(-5, 3, 0), Vector3d::UnitX(), 30.0));
  EXPECT_FALSE(w.castRay(Vector3d(-5, 0, 0), -Vector3d::UnitX(), 30.0));
}

TEST(VoxelWorldRay, MaxRangeIsExclusive) {
  const VoxelWorld w = wallWorld();
  const Vector3d origin(0.0625, 0.0625, 0.0625);
  EXPECT_FALSE(w.castRay(origin, Vector3d::UnitX(), 0.9));
  EXPECT_FALSE(w.castRay(origin, Vector3d::UnitX(), 0.9375));
  EXPECT_TRUE(w.castRay(origin, Vector3d::UnitX(), 0.94));
}

TEST(VoxelWorldRay, OriginInsideAnOccupiedVoxelHitsAtZero) {
  const VoxelWorld w = wallWorld();
  const Vector3d dir = Vector3d(1, 2, 3).normalized();
  const auto hit = w.castRay(Vector3d(1.1, 0.0, 0.0), dir, 5.0);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->range_m, 0.0);
  EXPECT_EQ(hit->normal, -dir);
}

/// Reference: march in tiny steps and report the first occupied sample.
double marchedRange(const VoxelWorld& w, const Vector3d& o, const Vector3d& d, double max_range, double step) {
  for (double t = 0.0; t < max_range; t += step) {
    if (w.occupied(o + t * d)) return t;
  }
  return INFINITY;
}

TEST(VoxelWorldRay, AgreesWithRayMarchingOnRandomWorlds) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  // Dimensions that are not multiples of the 8³ bricks, and a grid off the origin.
  VoxelWorld w(kV, Vector3i(-13, 5, -7), Vector3i(37, 29, 23));
  const Eigen::AlignedBox3d b = w.bounds();
  for (int i = 0; i < 25; ++i) {
    const Vector3d c = b.min() + (b.max() - b.min()).cwiseProduct(Vector3d(u(rng) + 1, u(rng) + 1, u(rng) + 1) / 2);
    const Vector3d half(0.1 + 0.3 * std::abs(u(rng)), 0.1 + 0.3 * std::abs(u(rng)), 0.1 + 0.3 * std::abs(u(rng)));
    w.fillBox(Eigen::AlignedBox3d(c - half, c + half), 0.5f);
  }
  const double step = 1e-4;
  int hits = 0;
  for (int i = 0; i < 400; ++i) {
    // Origins inside and up to 1 m outside the grid.
    const Vector3d o = b.center() + (b.sizes() / 2 + Vector3d::Constant(1.0)).cwiseProduct(Vector3d(u(rng), u(rng), u(rng)));
    const Vector3d d = Vector3d(u(rng), u(rng), u(rng)).normalized();
    const double reference = marchedRange(w, o, d, 8.0, step);
    const auto hit = w.castRay(o, d, 8.0);
    if (std::isinf(reference)) {
      EXPECT_FALSE(hit && hit->range_m < 8.0 - step) << "ray " << i;
      continue;
    }
    ASSERT_TRUE(hit) << "ray " << i << " reference " << reference;
    ++hits;
    EXPECT_LE(hit->range_m, reference + 1e-12) << "ray " << i;
    EXPECT_GE(hit->range_m, reference - step - 1e-12) << "ray " << i;
    // The entered voxel is the occupied one just past the hit point.
    EXPECT_TRUE(w.occupied(hit->point_m + 1e-9 * d)) << "ray " << i;
  }
  EXPECT_GT(hits, 40);
}

}  // namespace
}  // namespace rmap::sim
