#include "app/layer_tiles.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rmap::app {

namespace {

/// Grey of a pixel showing `value` (a probability or a reflectivity, clamped to [0, 1]).
uint8_t layerGrey(Layer2d layer, float value) {
  const float grey = layer == Layer2d::kOccupancy ? 1.0f - value : value;
  return static_cast<uint8_t>(std::lround(255.0f * grey));
}

float layerValue(const Grid2dSource& grid, Layer2d layer, const Eigen::Vector2i& cell) {
  return layer == Layer2d::kOccupancy ? grid.probability(cell) : grid.reflectivity(cell);
}

}  // namespace

std::optional<Layer2d> parseLayer2d(std::string_view name) {
  if (name == "occupancy") return Layer2d::kOccupancy;
  if (name == "reflectivity") return Layer2d::kReflectivity;
  return std::nullopt;
}

const char* toString(Layer2d layer) { return layer == Layer2d::kOccupancy ? "occupancy" : "reflectivity"; }

void checkLayerTile(const LayerTileKey& key) {
  if (key.z < 0 || key.z > kLayerMaxZoom) {
    throw std::invalid_argument("layer tile z must be in [0, " + std::to_string(kLayerMaxZoom) + "]");
  }
  const int64_t n = int64_t{1} << key.z;
  if (key.x < 0 || key.x >= n || key.y < 0 || key.y >= n) {
    throw std::invalid_argument("layer tile x and y must be in [0, " + std::to_string(n - 1) + "] at z " +
                                std::to_string(key.z));
  }
}

CellRange layerTileCells(const LayerTileKey& key) {
  const int64_t edge = kLayerExtentCells >> key.z;
  const int64_t x0 = -kLayerExtentCells / 2 + key.x * edge;
  const int64_t y1 = kLayerExtentCells / 2 - key.y * edge;  // slippy y grows towards −y
  CellRange range;
  range.min = {x0, y1 - edge};
  range.max = {x0 + edge, y1};
  return range;
}

Eigen::AlignedBox2d layerTileBounds(const LayerTileKey& key, double resolution_m) {
  const double extent_m = static_cast<double>(kLayerExtentCells) * resolution_m;
  const double edge_m = extent_m / static_cast<double>(int64_t{1} << key.z);
  const double x0 = -extent_m / 2 + static_cast<double>(key.x) * edge_m;
  const double y1 = extent_m / 2 - static_cast<double>(key.y) * edge_m;
  return Eigen::AlignedBox2d(Eigen::Vector2d(x0, y1 - edge_m), Eigen::Vector2d(x0 + edge_m, y1));
}

GrayAlphaImage renderLayerTile(const Grid2dSource& grid, Layer2d layer, const LayerTileKey& key) {
  checkLayerTile(key);
  constexpr int kPx = kLayerTilePx;
  GrayAlphaImage image{kPx, kPx, std::vector<uint8_t>(size_t{2} * kPx * kPx, 0)};
  const Eigen::AlignedBox2i known = grid.knownCells();
  if (known.isEmpty()) return image;
  const int shift_down = std::max(0, kLayerNativeZoom - key.z);  // cells per pixel = 2^shift_down
  const int shift_up = std::max(0, key.z - kLayerNativeZoom);    // pixels per cell = 2^shift_up
  const CellRange tile = layerTileCells(key);
  const int64_t x_lo = std::max<int64_t>(tile.min.x(), known.min().x());
  const int64_t x_hi = std::min<int64_t>(tile.max.x(), int64_t{known.max().x()} + 1);
  const int64_t y_lo = std::max<int64_t>(tile.min.y(), known.min().y());
  const int64_t y_hi = std::min<int64_t>(tile.max.y(), int64_t{known.max().y()} + 1);
  if (x_lo >= x_hi || y_lo >= y_hi) return image;
  std::vector<float> best(size_t{kPx} * kPx, -1.0f);
  const int block = 1 << shift_up;
  for (int64_t cy = y_lo; cy < y_hi; ++cy) {
    for (int64_t cx = x_lo; cx < x_hi; ++cx) {
      const Eigen::Vector2i cell(static_cast<int>(cx), static_cast<int>(cy));
      float value = layerValue(grid, layer, cell);
      if (!std::isfinite(value)) continue;
      value = std::clamp(value, 0.0f, 1.0f);
      const int64_t col0 = ((cx - tile.min.x()) << shift_up) >> shift_down;
      const int64_t row0 = ((tile.max.y() - 1 - cy) << shift_up) >> shift_down;
      for (int64_t row = row0; row < row0 + block; ++row) {
        for (int64_t col = col0; col < col0 + block; ++col) {
          float& b = best[static_cast<size_t>(row * kPx + col)];
          b = std::max(b, value);
        }
      }
    }
  }
  for (size_t i = 0; i < best.size(); ++i) {
    if (best[i] < 0.0f) continue;
    image.pixels[2 * i] = layerGrey(layer, best[i]);
    image.pixels[2 * i + 1] = 255;
  }
  return image;
}

GrayAlphaImage renderLayerImage(const Grid2dSource& grid, Layer2d layer, size_t max_pixels) {
  const Eigen::AlignedBox2i known = grid.knownCells();
  if (known.isEmpty()) return {1, 1, std::vector<uint8_t>(2, 0)};
  const int width = known.max().x() - known.min().x() + 1;
  const int height = known.max().y() - known.min().y() + 1;
  const size_t pixels = static_cast<size_t>(width) * static_cast<size_t>(height);
  if (pixels > max_pixels) {
    throw std::length_error("the " + std::string(toString(layer)) + " layer is " + std::to_string(width) + " × " +
                            std::to_string(height) + " cells, more than " + std::to_string(max_pixels) +
                            " pixels; read it as tiles");
  }
  GrayAlphaImage image{width, height, std::vector<uint8_t>(2 * pixels, 0)};
  size_t i = 0;
  for (int y = known.max().y(); y >= known.min().y(); --y) {
    for (int x = known.min().x(); x <= known.max().x(); ++x, i += 2) {
      const float value = layerValue(grid, layer, {x, y});
      if (!std::isfinite(value)) continue;
      image.pixels[i] = layerGrey(layer, std::clamp(value, 0.0f, 1.0f));
      image.pixels[i + 1] = 255;
    }
  }
  return image;
}

}  // namespace rmap::app
