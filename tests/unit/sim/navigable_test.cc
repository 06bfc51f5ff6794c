#include "sim/navigable.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace rmap::sim {
namespace {

using Eigen::Vector3d;

/// 6 m × 6 m room (walls 0.1 m, 3 m high) with a floor at z = 0 and an optional platform.
VoxelWorld platformRoom(double platform_height = 0.0) {
  VoxelWorld w = VoxelWorld::covering(box(0, 0, -0.1, 6, 6, 3), 0.05);
  w.fillBox(box(0, 0, -0.1, 6, 6, 0), 0.3f);
  w.fillBox(box(0, 0, 0, 0.1, 6, 3), 0.5f);
  w.fillBox(box(5.9, 0, 0, 6, 6, 3), 0.5f);
  w.fillBox(box(0, 0, 0, 6, 0.1, 3), 0.5f);
  w.fillBox(box(0, 5.9, 0, 6, 6, 3), 0.5f);
  if (platform_height > 0) w.fillBox(box(3.0, 0.1, 0, 5.9, 5.9, platform_height), 0.4f);
  return w;
}

/// Horizontal gap between two rectangles (0 when they overlap).
double gap(const Eigen::AlignedBox2d& a, const Eigen::AlignedBox2d& b) {
  const double dx = std::max({0.0, a.min().x() - b.max().x(), b.min().x() - a.max().x()});
  const double dy = std::max({0.0, a.min().y() - b.max().y(), b.min().y() - a.max().y()});
  return std::hypot(dx, dy);
}

TEST(Navigable, FloorCellsKeepClearanceFromWallsAndFurniture) {
  VoxelWorld w = platformRoom();
  const Eigen::AlignedBox2d cabinet(Eigen::Vector2d(2.5, 2.5), Eigen::Vector2d(3.5, 3.5));
  w.fillBox(box(2.5, 2.5, 0, 3.5, 3.5, 1.0), 0.7f);
  const NavigableOptions o;
  const NavigableSpace space(w, o);
  ASSERT_GT(space.size(), 0u);
  EXPECT_DOUBLE_EQ(space.cellSize(), 0.1);
  EXPECT_NEAR(space.dominantFloorZ(), 0.0, 1e-12);
  const Eigen::AlignedBox2d inner(Eigen::Vector2d(0.1, 0.1), Eigen::Vector2d(5.9, 5.9));
  size_t floor_nodes = 0;
  bool near_wall = false;
  for (size_t i = 0; i < space.size(); ++i) {
    const int n = static_cast<int>(i);
    if (space.component(n) != 0) {
      EXPECT_NEAR(space.surfaceZ(n), 1.0, 1e-12);  // the cabinet top: a separate, unreachable place
      continue;
    }
    ++floor_nodes;
    EXPECT_NEAR(space.surfaceZ(n), 0.0, 1e-12);
    EXPECT_NEAR(space.sensorZ(n), 1.0, 1e-12);
    const Eigen::AlignedBox2d cell = space.cellBox(space.nodes()[i].cx, space.nodes()[i].cy);
    EXPECT_GE(gap(cell, cabinet), o.clearance_m - 1e-9);
    EXPECT_GE(cell.min().x() - inner.min().x(), o.clearance_m - 1e-9);
    EXPECT_GE(inner.max().y() - cell.max().y(), o.clearance_m - 1e-9);
    near_wall |= cell.min().x() - inner.min().x() < o.clearance_m + 0.1;
  }
  EXPECT_TRUE(near_wall);  // not more conservative than one cell
  // The free floor is 5.8² m² minus the cabinet's inflated footprint, less the wall margins.
  const double area = floor_nodes * 0.01;
  EXPECT_GT(area, 5.2 * 5.2 - 1.6 * 1.6 - 0.5);
  EXPECT_LT(area, 5.3 * 5.3 - 1.5 * 1.5);
  EXPECT_EQ(space.componentCount(), 2u);
}

TEST(Navigable, LowStepsConnectHighStepsSplit) {
  const NavigableSpace low(platformRoom(0.2), NavigableOptions{});
  EXPECT_EQ(low.componentCount(), 1u);
  const NavigableSpace high(platformRoom(0.4), NavigableOptions{});
  EXPECT_EQ(high.componentCount(), 2u);
  // Components are numbered by decreasing size.
  EXPECT_GE(high.componentSize(0), high.componentSize(1));
}

TEST(Navigable, KnownFreeSpaceBoundsTheSensor) {
  VoxelWorld w = platformRoom();
  // Only x < 3 m was observed free (around the sensor height).
  Eigen::Vector3i lo, hi;
  ASSERT_TRUE(w.voxelOf(Vector3d(0.1, 0.1, 0.0), lo));
  ASSERT_TRUE(w.voxelOf(Vector3d(2.99, 5.89, 2.99), hi));
  w.markKnownFree(VoxelBox(lo, hi));
  const NavigableSpace space(w, NavigableOptions{});
  ASSERT_GT(space.size(), 0u);
  for (size_t i = 0; i < space.size(); ++i) {
    const Vector3d s = space.sensorPosition(static_cast<int>(i));
    EXPECT_LT(space.cellBox(space.nodes()[i].cx, space.nodes()[i].cy).max().x(), 3.0 + 1e-9);
    EXPECT_TRUE(w.knownFree(s));
  }
}

TEST(Navigable, NothingWithoutFloorOrHeadroom) {
  VoxelWorld empty = VoxelWorld::covering(box(0, 0, 0, 4, 4, 3), 0.05);
  EXPECT_EQ(NavigableSpace(empty, NavigableOptions{}).size(), 0u);
  EXPECT_TRUE(std::isnan(NavigableSpace(empty, NavigableOptions{}).dominantFloorZ()));
  // The body (sensor 1 m + clearance) does not fit under a 1.1 m grid top.
  VoxelWorld low = VoxelWorld::covering(box(0, 0, -0.1, 4, 4, 1.1), 0.05);
  low.fillBox(box(0, 0, -0.1, 4, 4, 0), 0.3f);
  EXPECT_EQ(NavigableSpace(low, NavigableOptions{}).size(), 0u);
}

TEST(Navigable, RejectsBadOptions) {
  const VoxelWorld w = platformRoom();
  NavigableOptions o;
  o.clearance_m = 0.0;
  EXPECT_THROW(NavigableSpace(w, o), std::invalid_argument);
  o = NavigableOptions{};
  o.sensor_height_m = 0.1;
  EXPECT_THROW(NavigableSpace(w, o), std::invalid_argument);
  o = NavigableOptions{};
  o.cell_m = -1.0;
  EXPECT_THROW(NavigableSpace(w, o), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::sim
