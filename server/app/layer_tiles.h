#pragma once
/// @file layer_tiles.h
/// Raster tiles of a map's 2D layers (occupancy, reflectivity) in the slippy
/// map convention, and the read interface the rasters are drawn from.
///
/// Tile pyramid: zoom z holds 2^z × 2^z tiles of kLayerTilePx × kLayerTilePx
/// pixels. Zoom 0 is one tile covering the square of kLayerExtentCells cells
/// per axis centred on the map origin: cells [−32768, 32768) on x and y, i.e.
/// [−E/2, E/2) m with E = 65536 · resolution (3276.8 m at 0.05 m). At zoom z a
/// pixel spans 2^(8−z) cells (z ≤ 8; z = kLayerNativeZoom is one cell per
/// pixel) or 1/2^(z−8) of a cell (z > 8). Tile x grows towards +x of the map
/// frame; tile y and pixel rows grow southwards, i.e. towards −y of the map
/// frame (row 0 of tile y = 0 is the +y edge of the extent).

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace rmap::app {

inline constexpr int kLayerTilePx = 256;
inline constexpr int kLayerNativeZoom = 8;  ///< one cell per pixel
inline constexpr int kLayerMaxZoom = 10;    ///< 4 × 4 pixels per cell
inline constexpr int64_t kLayerExtentCells = int64_t{kLayerTilePx} << kLayerNativeZoom;
// Tile edges fall on whole cells at every zoom.
static_assert((kLayerExtentCells >> kLayerMaxZoom) >= 1);

/// What the rasters read from a map (the SLAM grid's finest level).
class Grid2dSource {
 public:
  virtual ~Grid2dSource() = default;
  virtual double resolutionM() const = 0;
  /// Inclusive bounds of the cells observed so far (empty box when none).
  virtual Eigen::AlignedBox2i knownCells() const = 0;
  /// Occupancy probability, NaN when unknown.
  virtual float probability(const Eigen::Vector2i& cell) const = 0;
  /// Fused calibrated reflectivity (1 = the calibration's reference surface), NaN when none.
  virtual float reflectivity(const Eigen::Vector2i& cell) const = 0;
};

enum class Layer2d { kOccupancy, kReflectivity };
/// "occupancy" or "reflectivity"; nullopt otherwise.
std::optional<Layer2d> parseLayer2d(std::string_view name);
const char* toString(Layer2d layer);

struct LayerTileKey {
  int z = 0;
  int64_t x = 0;
  int64_t y = 0;
};

/// @throws std::invalid_argument unless 0 ≤ z ≤ kLayerMaxZoom and 0 ≤ x, y < 2^z
void checkLayerTile(const LayerTileKey& key);

/// Cells a tile covers, half-open: x ∈ [min.x, max.x), y ∈ [min.y, max.y);
/// 2^(16−z) cells per axis.
struct CellRange {
  Eigen::Matrix<int64_t, 2, 1> min;
  Eigen::Matrix<int64_t, 2, 1> max;
};
CellRange layerTileCells(const LayerTileKey& key);

/// Map-frame square a tile covers (m).
Eigen::AlignedBox2d layerTileBounds(const LayerTileKey& key, double resolution_m);

/// 8-bit grey + alpha pixels, row 0 at the top (the +y side), 2 bytes per pixel.
struct GrayAlphaImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> pixels;
};

/// Draws one tile. Occupancy: grey = 255·(1 − p), opaque where known.
/// Reflectivity: grey = 255·min(ρ, 1), opaque where a reflectivity was fused.
/// A pixel covering several cells takes the largest value among them (walls
/// and markers stay visible when zoomed out); unknown pixels are transparent.
GrayAlphaImage renderLayerTile(const Grid2dSource& grid, Layer2d layer, const LayerTileKey& key);

/// The whole layer at one pixel per cell over the known cells' bounding box
/// (row 0 at its +y edge, as map_server images), pixels as in the tiles; a
/// 1×1 transparent image when nothing is known.
/// @param max_pixels  larger images are refused (a grid grows with the area driven)
/// @throws std::length_error naming the size when width × height > max_pixels
GrayAlphaImage renderLayerImage(const Grid2dSource& grid, Layer2d layer, size_t max_pixels);

}  // namespace rmap::app
