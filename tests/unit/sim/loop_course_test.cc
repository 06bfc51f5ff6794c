#include "sim/loop_course.h"

#include <gtest/gtest.h>

#include <set>
#include <stdexcept>

namespace rmap::sim {
namespace {

TEST(LoopCourse, CorridorAroundABlockWithFreeCentreLine) {
  const LoopCourse c = makeLoopCourse({}, 3);
  ASSERT_EQ(c.centerline_m.size(), 4u);
  const Eigen::Vector2d corner = c.centerline_m[0];
  EXPECT_DOUBLE_EQ(corner.x(), 1.5);
  // The lane (±0.8 m around the centre line) is free from floor to ceiling along every edge.
  for (size_t i = 0; i < 4; ++i) {
    const Eigen::Vector2d a = c.centerline_m[i], b = c.centerline_m[(i + 1) % 4];
    const Eigen::Vector2d side = Eigen::Vector2d(-(b - a).y(), (b - a).x()).normalized();
    for (double t = 0.0; t <= 1.0; t += 0.02) {
      for (double d : {-0.75, 0.0, 0.75}) {
        const Eigen::Vector2d p = a + t * (b - a) + d * side;
        for (double z : {0.1, 1.0, 2.9}) EXPECT_FALSE(c.world.occupied({p.x(), p.y(), z})) << p.transpose() << " " << z;
      }
    }
  }
  // Floor, ceiling, the outer wall and the central block are there.
  EXPECT_TRUE(c.world.occupied({1.5, 1.5, -0.05}));
  EXPECT_TRUE(c.world.occupied({1.5, 1.5, 3.05}));
  EXPECT_TRUE(c.world.occupied({-0.05, 6.0, 1.0}));
  EXPECT_TRUE(c.world.occupied({10.0, 3.05, 1.0}));
}

TEST(LoopCourse, WallsCarryVariedReflectivity) {
  const LoopCourse c = makeLoopCourse({}, 3);
  std::set<int> levels;
  for (double x = 0.5; x < 19.5; x += 0.1) {
    for (double z = 0.1; z < 2.9; z += 0.3) levels.insert(std::lround(c.world.reflectivityAt({x, -0.025, z}) * 20));
  }
  EXPECT_GE(levels.size(), 10u);  // posters of many shades, not one paint
}

TEST(LoopCourse, SeedDecides) {
  const LoopCourse a = makeLoopCourse({}, 1), b = makeLoopCourse({}, 1), d = makeLoopCourse({}, 2);
  int differ_ab = 0, differ_ad = 0;
  for (double x = 0.5; x < 19.5; x += 0.25) {
    for (double z = 0.1; z < 2.9; z += 0.25) {
      const Eigen::Vector3d p(x, -0.025, z);
      differ_ab += a.world.reflectivityAt(p) != b.world.reflectivityAt(p);
      differ_ad += a.world.reflectivityAt(p) != d.world.reflectivityAt(p);
    }
  }
  EXPECT_EQ(differ_ab, 0);
  EXPECT_GT(differ_ad, 100);
}

TEST(LoopCourse, BadOptionsThrow) {
  LoopCourseOptions o;
  o.corridor_width_m = 2.0;
  EXPECT_THROW(makeLoopCourse(o, 1), std::invalid_argument);
  o = {};
  o.size_x_m = 7.0;
  EXPECT_THROW(makeLoopCourse(o, 1), std::invalid_argument);
  o = {};
  o.voxel_noise = -0.1;
  EXPECT_THROW(makeLoopCourse(o, 1), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::sim
