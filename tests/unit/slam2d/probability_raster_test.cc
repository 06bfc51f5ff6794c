#include "slam2d/probability_raster.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace rmap::slam2d {
namespace {

TEST(ProbabilityRaster, CellsAreFlooredFromTheOriginAndOutsideReadsOutsideP) {
  ProbabilityRaster raster;
  raster.origin_m = {-1.0, 2.0};
  raster.resolution_m = 0.5;
  raster.width = 3;
  raster.height = 2;
  raster.p = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f};
  raster.outside_p = 0.05f;
  EXPECT_NO_THROW(raster.validate());
  EXPECT_EQ(raster.cellOf({-1.0, 2.0}), Eigen::Vector2i(0, 0));
  EXPECT_EQ(raster.cellOf({-0.01, 2.99}), Eigen::Vector2i(1, 1));
  EXPECT_EQ(raster.cellOf({-1.01, 1.99}), Eigen::Vector2i(-1, -1));
  EXPECT_FLOAT_EQ(raster.at(2, 0), 0.3f);
  EXPECT_FLOAT_EQ(raster.at(0, 1), 0.4f);
  EXPECT_FLOAT_EQ(raster.at(3, 0), 0.05f);
  EXPECT_FLOAT_EQ(raster.at(0, -1), 0.05f);
}

TEST(ProbabilityRaster, MaxFilterThickensAPeakWithinItsRadiusOnly) {
  ProbabilityRaster raster;
  raster.origin_m = {0.0, 0.0};
  raster.resolution_m = 0.1;
  raster.width = 5;
  raster.height = 4;
  raster.p.assign(20, 0.1f);
  raster.p[1 * 5 + 2] = 0.9f;  // (2, 1)
  raster.p[3 * 5 + 4] = 0.4f;  // (4, 3), a corner
  raster.outside_p = 0.1f;
  const ProbabilityRaster once = maxFiltered(raster, 1);
  EXPECT_EQ(once.width, 5);
  EXPECT_EQ(once.height, 4);
  EXPECT_EQ(once.origin_m, raster.origin_m);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 5; ++x) {
      float expected = 0.1f;
      if (std::abs(x - 4) <= 1 && std::abs(y - 3) <= 1) expected = 0.4f;
      if (std::abs(x - 2) <= 1 && std::abs(y - 1) <= 1) expected = 0.9f;
      EXPECT_FLOAT_EQ(once.at(x, y), expected) << x << "," << y;
    }
  EXPECT_EQ(maxFiltered(raster, 0).p, raster.p);
  EXPECT_FLOAT_EQ(maxFiltered(raster, 2).at(0, 3), 0.9f);
  EXPECT_FLOAT_EQ(maxFiltered(raster, 2).at(4, 0), 0.9f);
  EXPECT_THROW(maxFiltered(raster, -1), std::invalid_argument);
}

TEST(ProbabilityRaster, ValidateNamesTheBrokenInvariant) {
  ProbabilityRaster raster;
  raster.width = 2;
  raster.height = 2;
  raster.p = {0.0f, 0.5f, 1.0f, 0.2f};
  EXPECT_NO_THROW(raster.validate());
  ProbabilityRaster bad = raster;
  bad.p.pop_back();
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = raster;
  bad.p[1] = 1.5f;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = raster;
  bad.p[2] = NAN;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = raster;
  bad.resolution_m = 0.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = raster;
  bad.width = 0;
  bad.p.clear();
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = raster;
  bad.outside_p = -0.1f;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

TEST(ProbabilityRaster, FromGridCopiesTheBoxAndFillsUnknown) {
  OccupancyGrid grid(0.1);
  // One beam from (0.05, 0.05) along +x to a wall at x = 0.55: cells 0..4 free, 5 hit.
  const std::vector<Ray> rays{{{0.55, 0.05}, true}};
  grid.insert({0.05, 0.05}, rays, OccupancyUpdate{}, 100.0);
  const Eigen::AlignedBox2i box(Eigen::Vector2i(-2, -1), Eigen::Vector2i(6, 1));
  const ProbabilityRaster raster = rasterFromGrid(grid, box, 0.1f);
  EXPECT_EQ(raster.width, 9);
  EXPECT_EQ(raster.height, 3);
  EXPECT_DOUBLE_EQ(raster.origin_m.x(), -0.2);
  EXPECT_DOUBLE_EQ(raster.origin_m.y(), -0.1);
  EXPECT_FLOAT_EQ(raster.outside_p, 0.1f);
  // Grid cell (c, 0) is raster cell (c + 2, 1).
  EXPECT_FLOAT_EQ(raster.at(5 + 2, 1), grid.probability({5, 0}));
  EXPECT_GT(raster.at(5 + 2, 1), 0.7f);
  EXPECT_FLOAT_EQ(raster.at(2 + 2, 1), grid.probability({2, 0}));
  EXPECT_LT(raster.at(2 + 2, 1), 0.45f);
  EXPECT_FLOAT_EQ(raster.at(0, 0), 0.1f);   // never observed
  EXPECT_FLOAT_EQ(raster.at(8, 1), 0.1f);   // past the wall
  EXPECT_EQ(raster.cellOf({0.55, 0.05}), Eigen::Vector2i(7, 1));
  EXPECT_THROW(rasterFromGrid(grid, Eigen::AlignedBox2i(), 0.1f), std::invalid_argument);
  EXPECT_THROW(rasterFromGrid(grid, box, 1.2f), std::invalid_argument);
}

TEST(ProbabilityRaster, FromScansRaysOutFreeSpaceAndMarksEndpoints) {
  // A wall at x = 2.025 m seen from two poses, 41 beams each.
  std::vector<Eigen::Vector2d> a, b;
  const Pose2 pose_a{0.0, 0.0, 0.0}, pose_b{0.5, 0.3, 0.2};
  for (int i = -20; i <= 20; ++i) {
    const Eigen::Vector2d wall(2.025, 0.05 * i);
    a.push_back(pose_a.inverse() * wall);
    b.push_back(pose_b.inverse() * wall);
  }
  const std::vector<PosedScan> scans{{pose_a, a}, {pose_b, b}};
  const ProbabilityRaster raster = rasterFromScans(scans, 0.05, 0.2f, OccupancyUpdate{}, 100.0, 3);
  EXPECT_NO_THROW(raster.validate());
  const Eigen::Vector2i wall = raster.cellOf({2.025, 0.025});
  const Eigen::Vector2i free = raster.cellOf({1.0, 0.025});
  EXPECT_GT(raster.at(wall.x(), wall.y()), 0.8f);
  EXPECT_NEAR(raster.at(free.x(), free.y()), 1.0 / (1.0 + std::exp(0.8)), 1e-6);  // two misses of −0.4
  // The margin: three unknown columns past the wall.
  EXPECT_EQ(raster.cellOf({2.025 + 0.05 * 3, 0.0}).x(), raster.width - 1);
  EXPECT_FLOAT_EQ(raster.at(raster.width - 1, wall.y()), 0.2f);
  EXPECT_THROW(rasterFromScans({}, 0.05, 0.2f), std::invalid_argument);
  EXPECT_THROW(rasterFromScans(scans, -0.05, 0.2f), std::invalid_argument);
  EXPECT_THROW(rasterFromScans(scans, 0.05, 0.2f, OccupancyUpdate{}, 100.0, -1), std::invalid_argument);
  std::vector<Eigen::Vector2d> nan_scan = a;
  nan_scan[0].y() = NAN;
  const std::vector<PosedScan> bad{{pose_a, nan_scan}};
  EXPECT_THROW(rasterFromScans(bad, 0.05, 0.2f), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::slam2d
