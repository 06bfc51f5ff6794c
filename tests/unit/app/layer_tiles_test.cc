#include "app/layer_tiles.h"

#include <gtest/gtest.h>

#include "fake_grid2d.h"

namespace rmap::app {
namespace {

uint8_t grey(const GrayAlphaImage& image, int col, int row) { return image.pixels[2 * (row * image.width + col)]; }
uint8_t alpha(const GrayAlphaImage& image, int col, int row) {
  return image.pixels[2 * (row * image.width + col) + 1];
}

TEST(LayerTiles, ZoomZeroCoversTheWholeExtentCentredOnTheOrigin) {
  const CellRange cells = layerTileCells({0, 0, 0});
  EXPECT_EQ(cells.min.x(), -32768);
  EXPECT_EQ(cells.min.y(), -32768);
  EXPECT_EQ(cells.max.x(), 32768);
  EXPECT_EQ(cells.max.y(), 32768);
  const Eigen::AlignedBox2d bounds = layerTileBounds({0, 0, 0}, 0.05);
  EXPECT_DOUBLE_EQ(bounds.min().x(), -1638.4);
  EXPECT_DOUBLE_EQ(bounds.max().y(), 1638.4);
}

TEST(LayerTiles, TileYGrowsTowardsMinusYOfTheMapFrame) {
  // At zoom 1 tile (0, 0) is the north-west quarter: x < 0, y ≥ 0.
  const CellRange nw = layerTileCells({1, 0, 0});
  EXPECT_EQ(nw.min.x(), -32768);
  EXPECT_EQ(nw.max.x(), 0);
  EXPECT_EQ(nw.min.y(), 0);
  EXPECT_EQ(nw.max.y(), 32768);
  const CellRange se = layerTileCells({1, 1, 1});
  EXPECT_EQ(se.min.x(), 0);
  EXPECT_EQ(se.max.y(), 0);
  // The native zoom has one cell per pixel: 256 cells per tile.
  const CellRange native = layerTileCells({kLayerNativeZoom, 128, 127});
  EXPECT_EQ(native.max.x() - native.min.x(), 256);
  EXPECT_EQ(native.min.x(), 0);
  EXPECT_EQ(native.min.y(), 0);
}

TEST(LayerTiles, BadKeysAreRefused) {
  EXPECT_THROW(checkLayerTile({-1, 0, 0}), std::invalid_argument);
  EXPECT_THROW(checkLayerTile({kLayerMaxZoom + 1, 0, 0}), std::invalid_argument);
  EXPECT_THROW(checkLayerTile({2, 4, 0}), std::invalid_argument);
  EXPECT_THROW(checkLayerTile({2, 0, -1}), std::invalid_argument);
  EXPECT_NO_THROW(checkLayerTile({2, 3, 3}));
  EXPECT_EQ(parseLayer2d("occupancy"), Layer2d::kOccupancy);
  EXPECT_EQ(parseLayer2d("reflectivity"), Layer2d::kReflectivity);
  EXPECT_FALSE(parseLayer2d("height"));
}

TEST(LayerTiles, NativeZoomDrawsOneCellPerPixelWithRowZeroAtTheTop) {
  testing::FakeGrid2d grid(0.05);
  grid.set(0, 0, 0.8f, 0.95f);   // bottom-left cell of tile (8, 128, 127)
  grid.set(5, 255, 0.2f, 0.2f);  // top row of that tile
  const LayerTileKey key{kLayerNativeZoom, 128, 127};
  const GrayAlphaImage occupancy = renderLayerTile(grid, Layer2d::kOccupancy, key);
  ASSERT_EQ(occupancy.width, 256);
  ASSERT_EQ(occupancy.pixels.size(), 256u * 256u * 2u);
  EXPECT_EQ(alpha(occupancy, 0, 255), 255);
  EXPECT_EQ(grey(occupancy, 0, 255), 51);  // 255 · (1 − 0.8)
  EXPECT_EQ(alpha(occupancy, 5, 0), 255);
  EXPECT_EQ(grey(occupancy, 5, 0), 204);  // 255 · (1 − 0.2)
  EXPECT_EQ(alpha(occupancy, 1, 255), 0);  // unknown: transparent
  const GrayAlphaImage reflectivity = renderLayerTile(grid, Layer2d::kReflectivity, key);
  EXPECT_EQ(grey(reflectivity, 0, 255), 242);  // 255 · 0.95
  EXPECT_EQ(grey(reflectivity, 5, 0), 51);
  // The neighbouring tile to the west holds neither cell.
  const GrayAlphaImage west = renderLayerTile(grid, Layer2d::kOccupancy, {kLayerNativeZoom, 127, 127});
  for (size_t i = 1; i < west.pixels.size(); i += 2) ASSERT_EQ(west.pixels[i], 0);
}

TEST(LayerTiles, ZoomedOutPixelsKeepTheMostOccupiedCell) {
  testing::FakeGrid2d grid(0.05);
  // Zoom 6: 4 × 4 cells per pixel. Free cells with one wall cell in the same pixel.
  for (int x = 0; x < 4; ++x) {
    for (int y = 0; y < 4; ++y) grid.set(x, y, 0.12f);
  }
  grid.set(3, 2, 0.97f);
  const GrayAlphaImage image = renderLayerTile(grid, Layer2d::kOccupancy, {6, 32, 31});
  EXPECT_EQ(alpha(image, 0, 255), 255);
  EXPECT_EQ(grey(image, 0, 255), 8);  // 255 · (1 − 0.97)
}

TEST(LayerTiles, ZoomedInCellsCoverBlocksOfPixels) {
  testing::FakeGrid2d grid(0.05);
  grid.set(0, 0, 0.9f);
  // Zoom 10: 4 × 4 pixels per cell; cell (0, 0) is the bottom-left block of tile (10, 512, 511).
  const GrayAlphaImage image = renderLayerTile(grid, Layer2d::kOccupancy, {10, 512, 511});
  for (int row = 252; row < 256; ++row) {
    for (int col = 0; col < 4; ++col) EXPECT_EQ(alpha(image, col, row), 255) << col << "," << row;
  }
  EXPECT_EQ(alpha(image, 4, 255), 0);
  EXPECT_EQ(alpha(image, 0, 251), 0);
}

}  // namespace
}  // namespace rmap::app

namespace rmap::app {
namespace {

TEST(LayerTiles, WholeLayerImageCoversTheKnownCellsWithRowZeroAtPlusY) {
  testing::FakeGrid2d grid(0.05);
  grid.set(-3, 4, 0.8f, 0.25f);  // top-left pixel
  grid.set(2, -1, 0.2f);         // bottom-right pixel, no reflectivity
  const GrayAlphaImage occupancy = renderLayerImage(grid, Layer2d::kOccupancy, 1000);
  ASSERT_EQ(occupancy.width, 6);
  ASSERT_EQ(occupancy.height, 6);
  const auto pixel = [](const GrayAlphaImage& image, int col, int row) {
    const size_t i = 2 * static_cast<size_t>(row * image.width + col);
    return std::pair<int, int>(image.pixels[i], image.pixels[i + 1]);
  };
  EXPECT_EQ(pixel(occupancy, 0, 0), (std::pair<int, int>(51, 255)));   // 255 · (1 − 0.8)
  EXPECT_EQ(pixel(occupancy, 5, 5), (std::pair<int, int>(204, 255)));  // 255 · (1 − 0.2)
  EXPECT_EQ(pixel(occupancy, 1, 0), (std::pair<int, int>(0, 0)));      // unknown: transparent
  const GrayAlphaImage reflectivity = renderLayerImage(grid, Layer2d::kReflectivity, 1000);
  EXPECT_EQ(pixel(reflectivity, 0, 0), (std::pair<int, int>(64, 255)));  // 255 · 0.25
  EXPECT_EQ(pixel(reflectivity, 5, 5), (std::pair<int, int>(0, 0)));     // no reflectivity fused
  // The same pixels as the native-zoom tile holding them.
  const GrayAlphaImage tile = renderLayerTile(grid, Layer2d::kOccupancy, {8, (-3 + 32768) >> 8, (32767 - 4) >> 8});
  EXPECT_EQ(pixel(tile, (-3 + 32768) & 255, (32767 - 4) & 255), pixel(occupancy, 0, 0));
}

TEST(LayerTiles, WholeLayerImageOfNothingAndOfTooMuch) {
  testing::FakeGrid2d grid(0.05);
  const GrayAlphaImage empty = renderLayerImage(grid, Layer2d::kReflectivity, 1);
  EXPECT_EQ(empty.width, 1);
  EXPECT_EQ(empty.pixels, (std::vector<uint8_t>{0, 0}));
  grid.set(0, 0, 0.5f);
  grid.set(99, 9, 0.5f);
  EXPECT_NO_THROW(renderLayerImage(grid, Layer2d::kOccupancy, 1000));
  EXPECT_THROW(renderLayerImage(grid, Layer2d::kOccupancy, 999), std::length_error);
}

}  // namespace
}  // namespace rmap::app
