#pragma once
/// @file grid2d_export.h
/// The occupancy layer as ROS map_server reads it: a PGM image and its YAML.
///
/// The image covers the known cells' bounding box, one pixel per cell, row 0
/// at the +y edge (map_server puts the image's lower-left pixel at `origin`).
/// Pixels are trinary: 0 occupied (p ≥ kOccupiedThresh), 254 free
/// (p ≤ kFreeThresh), 205 unknown (never observed, or in between), which
/// map_server reads back the same way with negate 0 and the thresholds below.

#include <string>

#include "app/layer_tiles.h"

namespace rmap::app {

inline constexpr double kOccupiedThresh = 0.65;
inline constexpr double kFreeThresh = 0.196;
inline constexpr uint8_t kPgmOccupied = 0;
inline constexpr uint8_t kPgmFree = 254;
inline constexpr uint8_t kPgmUnknown = 205;

/// Trinary PGM value of an occupancy probability (NaN = unknown).
uint8_t pgmValue(float probability);

/// P5 image of the known cells; a 1×1 unknown image when nothing is known.
std::string exportGridPgm(const Grid2dSource& grid);

/// map_server YAML naming `image`: resolution, origin [x, y, yaw] of the
/// lower-left pixel (m), negate 0 and the thresholds.
std::string exportGridYaml(const Grid2dSource& grid, const std::string& image);

}  // namespace rmap::app
