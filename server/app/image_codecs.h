#pragma once
/// @file image_codecs.h
/// Image files of the 2D layers: PNG (libpng) and binary PGM.

#include <cstdint>
#include <span>
#include <string>

#include "app/layer_tiles.h"

namespace rmap::app {

/// PNG, 8-bit grey + alpha, no interlace.
/// @throws std::invalid_argument when the pixel count does not match the size
/// @throws std::runtime_error when libpng fails
std::string encodePng(const GrayAlphaImage& image);

/// Binary PGM (P5, maxval 255) of `pixels`, row 0 first (the top row).
/// @throws std::invalid_argument when the pixel count does not match the size
std::string encodePgm(int width, int height, std::span<const uint8_t> pixels);

}  // namespace rmap::app
