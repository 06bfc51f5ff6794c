#include "app/grid2d_export.h"

#include <gtest/gtest.h>

#include "fake_grid2d.h"

namespace rmap::app {
namespace {

TEST(Grid2dExport, TrinaryValuesFollowTheThresholds) {
  EXPECT_EQ(pgmValue(0.97f), kPgmOccupied);
  EXPECT_EQ(pgmValue(0.66f), kPgmOccupied);
  EXPECT_EQ(pgmValue(0.64f), kPgmUnknown);
  EXPECT_EQ(pgmValue(0.12f), kPgmFree);
  EXPECT_EQ(pgmValue(0.5f), kPgmUnknown);
  EXPECT_EQ(pgmValue(NAN), kPgmUnknown);
}

TEST(Grid2dExport, PgmCoversTheKnownCellsWithTheTopRowAtMaxY) {
  testing::FakeGrid2d grid(0.05);
  grid.set(-2, 3, 0.9f);   // top-left
  grid.set(0, 1, 0.1f);    // bottom-right
  const std::string pgm = exportGridPgm(grid);
  const std::string header = "P5\n3 3\n255\n";
  ASSERT_EQ(pgm.substr(0, header.size()), header);
  const std::string pixels = pgm.substr(header.size());
  ASSERT_EQ(pixels.size(), 9u);
  EXPECT_EQ(static_cast<uint8_t>(pixels[0]), kPgmOccupied);
  EXPECT_EQ(static_cast<uint8_t>(pixels[8]), kPgmFree);
  for (int i = 1; i < 8; ++i) EXPECT_EQ(static_cast<uint8_t>(pixels[i]), kPgmUnknown) << i;
}

TEST(Grid2dExport, YamlPutsTheOriginAtTheLowerLeftCell) {
  testing::FakeGrid2d grid(0.05);
  grid.set(-2, 3, 0.9f);
  grid.set(0, 1, 0.1f);
  EXPECT_EQ(exportGridYaml(grid, "grid2d.pgm"),
            "image: grid2d.pgm\nresolution: 0.05\norigin: [-0.1, 0.05, 0.0]\nnegate: 0\noccupied_thresh: 0.65\n"
            "free_thresh: 0.196\nmode: trinary\n");
}

TEST(Grid2dExport, AnEmptyGridIsOneUnknownPixel) {
  const testing::FakeGrid2d grid(0.1);
  EXPECT_EQ(exportGridPgm(grid), std::string("P5\n1 1\n255\n") + static_cast<char>(kPgmUnknown));
}

}  // namespace
}  // namespace rmap::app
