#include "sim/building.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <set>
#include <stdexcept>

#include "sim/lidar.h"
#include "sim/navigable.h"

namespace rmap::sim {
namespace {

using Eigen::Vector3d;

BuildingOptions fastOptions() {
  BuildingOptions o;
  o.voxel_m = 0.05;  // coarser than the default to keep the tests quick
  return o;
}

/// Corridor-to-room doors: openings through a wall running along x.
std::vector<Eigen::AlignedBox3d> corridorDoors(const BuildingLayout& layout) {
  std::vector<Eigen::AlignedBox3d> doors;
  for (const auto& d : layout.doors) {
    if (d.sizes().y() < d.sizes().x()) doors.push_back(d);
  }
  return doors;
}

TEST(Building, DoorsLetRaysThroughAndWallsStopThem) {
  BuildingLayout layout;
  const VoxelWorld w = makeBuilding(fastOptions(), 1, &layout);
  ASSERT_EQ(layout.corridors.size(), 1u);
  ASSERT_GE(layout.rooms.size(), 4u);
  const auto& corridor = layout.corridors[0];
  const double yc = corridor.center().y(), z = 1.0;
  const auto doors = corridorDoors(layout);
  ASSERT_EQ(doors.size(), layout.rooms.size());  // one corridor door per room

  for (const auto& door : doors) {
    const double x = door.center().x();
    const bool south = door.center().y() < yc;
    const Vector3d dir(0.0, south ? -1.0 : 1.0, 0.0);
    const double far_face = south ? yc - door.min().y() : door.max().y() - yc;
    EXPECT_FALSE(w.occupied(Vector3d(x, door.center().y(), z)));
    const auto hit = w.castRay(Vector3d(x, yc, z), dir, 30.0);
    ASSERT_TRUE(hit);  // the building is closed
    EXPECT_GT(hit->range_m, far_face + 1.0) << "door at x = " << x;  // through, and past the clear approach
  }

  // Away from doors, a ray across the corridor stops at the corridor wall's face.
  int walls_hit = 0;
  for (double x = corridor.min().x() + 0.3; x < corridor.max().x() - 0.3; x += 0.5) {
    for (int side = 0; side < 2; ++side) {
      const double face = side == 0 ? corridor.min().y() : corridor.max().y();
      const bool near_door = std::any_of(doors.begin(), doors.end(), [&](const auto& d) {
        return std::abs(d.center().y() - face) < 0.5 && x > d.min().x() - 0.1 && x < d.max().x() + 0.1;
      });
      if (near_door) continue;
      const auto hit = w.castRay(Vector3d(x, yc, z), Vector3d(0.0, side == 0 ? -1.0 : 1.0, 0.0), 30.0);
      ASSERT_TRUE(hit);
      EXPECT_NEAR(hit->range_m, std::abs(face - yc), w.voxelSize() + 1e-9) << "x = " << x;
      EXPECT_EQ(std::abs(hit->normal.y()), 1.0);
      ++walls_hit;
    }
  }
  EXPECT_GT(walls_hit, 20);

  // Closed building: rays in every direction from the corridor hit something within its size.
  const auto dirs = lidarBeamDirections(LidarModel{});
  for (size_t i = 0; i < dirs.size(); i += 101) {
    const auto hit = w.castRay(Vector3d(corridor.center().x(), yc, 1.2), dirs[i], 100.0);
    ASSERT_TRUE(hit);
    EXPECT_LT(hit->range_m, 30.0);
  }
}

TEST(Building, StairsConnectTwoFloors) {
  BuildingOptions o = fastOptions();
  o.floors = 2;
  BuildingLayout layout;
  const VoxelWorld w = makeBuilding(o, 2, &layout);
  ASSERT_EQ(layout.stair_flights.size(), 1u);
  ASSERT_EQ(layout.stair_halls.size(), 2u);
  EXPECT_EQ(layout.corridors.size(), 2u);
  const auto& flight = layout.stair_flights[0];
  const int steps = static_cast<int>(std::lround(o.floor_height_m / layout.step_rise_m));
  EXPECT_LE(layout.step_rise_m, 0.19);
  EXPECT_NEAR(steps * layout.step_tread_m, flight.sizes().x(), 1e-9);
  // Looking down through the slab opening, the treads rise one step at a time.
  for (int k = 0; k < steps; ++k) {
    const Vector3d above(flight.min().x() + (k + 0.5) * layout.step_tread_m, flight.center().y(), o.floor_height_m + 1.0);
    const auto hit = w.castRay(above, -Vector3d::UnitZ(), 10.0);
    ASSERT_TRUE(hit) << "step " << k;
    EXPECT_NEAR(hit->point_m.z(), (k + 1) * layout.step_rise_m, w.voxelSize() + 1e-9) << "step " << k;
    EXPECT_EQ(hit->normal, Vector3d::UnitZ());
  }
  // The upper floor exists beside the opening and the flight is walkable: one
  // connected navigable component spans both storeys.
  const NavigableSpace space(w, NavigableOptions{});
  ASSERT_GT(space.size(), 0u);
  bool ground = false, upper = false;
  for (size_t i = 0; i < space.size(); ++i) {
    if (space.component(static_cast<int>(i)) != 0) continue;
    ground |= std::abs(space.surfaceZ(static_cast<int>(i))) < 1e-9;
    upper |= std::abs(space.surfaceZ(static_cast<int>(i)) - o.floor_height_m) < 1e-9;
  }
  EXPECT_TRUE(ground);
  EXPECT_TRUE(upper);

  BuildingLayout single;
  makeBuilding(fastOptions(), 2, &single);
  EXPECT_TRUE(single.stair_flights.empty());
  EXPECT_TRUE(single.stair_halls.empty());
}

TEST(Building, ReflectivitiesAreInRangeAndVaried) {
  BuildingLayout layout;
  const VoxelWorld w = makeBuilding(fastOptions(), 3, &layout);
  std::set<int> levels;
  size_t n = 0;
  w.forEachOccupiedVoxel([&](const Eigen::Vector3i& v) {
    if (++n % 17 != 0) return;
    const float r = w.reflectivityVoxel(v);
    EXPECT_GE(r, 0.05f - 1e-3f);
    EXPECT_LE(r, 1.0f);
    levels.insert(static_cast<int>(std::lround(r * 255)));
  });
  EXPECT_GT(levels.size(), 15u);
  // Markers are bright strips on the corridor walls, seen from the corridor.
  ASSERT_FALSE(layout.markers.empty());
  const double yc = layout.corridors[0].center().y();
  for (const auto& m : layout.markers) {
    const Vector3d target = m.center();
    const auto hit = w.castRay(Vector3d(target.x(), yc, target.z()),
                               Vector3d(0.0, target.y() < yc ? -1.0 : 1.0, 0.0), 30.0);
    ASSERT_TRUE(hit);
    EXPECT_GE(hit->reflectivity, 0.9f - 1e-3f);
  }
  // Floors are darker than the ceilings above them.
  for (const auto& room : layout.rooms) {
    const Vector3d c(room.center().x(), room.center().y(), 1.0);
    const auto down = w.castRay(c, -Vector3d::UnitZ(), 10.0), up = w.castRay(c, Vector3d::UnitZ(), 10.0);
    ASSERT_TRUE(down && up);
    if (std::abs(down->point_m.z()) > 1e-9) continue;  // furniture under the centre
    EXPECT_LE(down->reflectivity, 0.35f + 1e-3f);
    EXPECT_GE(up->reflectivity, 0.6f - 1e-3f);
  }
}

TEST(Building, FurnitureTopsExistAtAnyVoxelSize) {
  for (double voxel : {0.025, 0.05, 0.1}) {
    BuildingOptions o;
    o.voxel_m = voxel;
    BuildingLayout layout;
    const VoxelWorld w = makeBuilding(o, 6, &layout);
    ASSERT_FALSE(layout.furniture.empty());
    for (const auto& f : layout.furniture) {
      const auto hit = w.castRay(Vector3d(f.center().x(), f.center().y(), f.max().z() + 0.3), -Vector3d::UnitZ(), 5.0);
      ASSERT_TRUE(hit);
      EXPECT_NEAR(hit->point_m.z(), f.max().z(), voxel + 1e-9) << "voxel " << voxel << ", furniture at " << f.center().transpose();
    }
  }
}

TEST(Building, DeterministicGivenASeed) {
  BuildingLayout a, b, c;
  const VoxelWorld wa = makeBuilding(fastOptions(), 9, &a);
  const VoxelWorld wb = makeBuilding(fastOptions(), 9, &b);
  const VoxelWorld wc = makeBuilding(fastOptions(), 10, &c);
  EXPECT_EQ(wa.occupiedCount(), wb.occupiedCount());
  ASSERT_EQ(a.furniture.size(), b.furniture.size());
  for (size_t i = 0; i < a.furniture.size(); ++i) EXPECT_TRUE(a.furniture[i].isApprox(b.furniture[i]));
  size_t same = 0;
  wa.forEachOccupiedVoxel([&](const Eigen::Vector3i& v) { same += wb.occupiedVoxel(v) && wa.reflectivityVoxel(v) == wb.reflectivityVoxel(v); });
  EXPECT_EQ(same, wa.occupiedCount());
  EXPECT_NE(wa.occupiedCount(), wc.occupiedCount());
}

TEST(Building, RejectsBadOptions) {
  BuildingOptions o;
  o.floors = 0;
  EXPECT_THROW(makeBuilding(o, 1), std::invalid_argument);
  o = BuildingOptions{};
  o.size_y_m = 6.0;
  EXPECT_THROW(makeBuilding(o, 1), std::invalid_argument);
  o = BuildingOptions{};
  o.floors = 2;
  o.size_x_m = 12.0;  // the stair hall leaves no room for four rooms
  EXPECT_THROW(makeBuilding(o, 1), std::invalid_argument);
  o = BuildingOptions{};
  o.door_width_m = 2.5;
  EXPECT_THROW(makeBuilding(o, 1), std::invalid_argument);
  o = BuildingOptions{};
  o.floor_height_m = 2.0;
  EXPECT_THROW(makeBuilding(o, 1), std::invalid_argument);
}

// Not a pass/fail check: prints the ray-casting rate on the default building.
TEST(Building, RayCastRate) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  BuildingLayout layout;
  const VoxelWorld w = makeBuilding(BuildingOptions{}, 4, &layout);
  const double build_s = std::chrono::duration<double>(Clock::now() - t0).count();
  std::vector<Vector3d> origins;
  const auto& corridor = layout.corridors[0];
  for (int i = 1; i <= 3; ++i) {
    origins.emplace_back(corridor.min().x() + i * corridor.sizes().x() / 4, corridor.center().y(), 1.2);
  }
  for (size_t i = 0; i < layout.rooms.size(); i += 3) {
    origins.emplace_back(layout.rooms[i].center().x(), layout.rooms[i].center().y(), 1.2);
  }
  const auto dirs = lidarBeamDirections(LidarModel{});
  size_t rays = 0, hits = 0;
  double crossings = 0.0;  // voxel faces a plain dense DDA would cross
  const auto t1 = Clock::now();
  for (const Vector3d& o : origins) {
    for (const Vector3d& d : dirs) {
      const auto hit = w.castRay(o, d, 30.0);
      ++rays;
      if (hit) {
        ++hits;
        crossings += hit->range_m * d.cwiseAbs().sum() / w.voxelSize();
      }
    }
  }
  const double cast_s = std::chrono::duration<double>(Clock::now() - t1).count();
  std::printf("[ building ] %d x %d x %d voxels of %.3f m, %zu occupied, %.1f MiB, generated in %.2f s\n",
              w.dims().x(), w.dims().y(), w.dims().z(), w.voxelSize(), w.occupiedCount(), w.memoryBytes() / 1048576.0,
              build_s);
  std::printf("[ ray rate ] %zu rays (%zu hits) in %.3f s: %.2f M rays/s, %.1f M dense-DDA voxel steps/s\n", rays, hits,
              cast_s, rays / cast_s / 1e6, crossings / cast_s / 1e6);
  EXPECT_EQ(hits, rays);  // closed building
}

}  // namespace
}  // namespace rmap::sim
