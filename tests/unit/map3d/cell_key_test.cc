#include "map3d/cell_key.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace rmap::map3d {
namespace {

TEST(Grid, IndexClampsToTheAddressableRange) {
  const Grid grid(0.1);
  EXPECT_EQ(grid.index(0.05), 0);
  EXPECT_EQ(grid.index(-0.05), -1);
  EXPECT_EQ(grid.index(1e12), kCellLimit - 1);
  EXPECT_EQ(grid.index(-1e12), -kCellLimit);
  EXPECT_EQ(grid.index(std::numeric_limits<double>::infinity()), kCellLimit - 1);
  EXPECT_EQ(grid.index(std::numeric_limits<double>::quiet_NaN()), -kCellLimit);
}

TEST(Grid, FloatAndDoublePointsOfTheSameCoordinateShareTheirCell) {
  const Grid grid(0.1);
  // Coordinates a float cannot hold exactly, near cell edges far from the origin.
  for (double x = 3000.0; x < 3001.0; x += 0.1) {
    const Eigen::Vector3f as_float(static_cast<float>(x), 0.f, 0.f);
    CellKey from_float, from_double;
    ASSERT_TRUE(grid.cellChecked(as_float, from_float));
    ASSERT_TRUE(grid.cellChecked(Eigen::Vector3d(static_cast<double>(as_float.x()), 0.0, 0.0), from_double));
    EXPECT_EQ(from_float, from_double) << x;
  }
}

TEST(Grid, CellCheckedRefusesWhatIsOutsideTheRange) {
  const Grid grid(0.1);
  CellKey cell;
  EXPECT_TRUE(grid.cellChecked(Eigen::Vector3d(3276.75, -3276.75, 0.0), cell));
  EXPECT_EQ(cell, (CellKey{32767, -32768, 0}));
  EXPECT_FALSE(grid.cellChecked(Eigen::Vector3d(3276.85, 0.0, 0.0), cell));
  EXPECT_FALSE(grid.cellChecked(Eigen::Vector3d(0.0, std::nan(""), 0.0), cell));
  EXPECT_FALSE(grid.cellChecked(Eigen::Vector3f(0.f, 0.f, std::numeric_limits<float>::infinity()), cell));
}

}  // namespace
}  // namespace rmap::map3d
