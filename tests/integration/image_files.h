#pragma once
/// @file image_files.h
/// Readers of the 2D layers' files for end-to-end tests: PNG (grey + alpha,
/// libpng), the key: value lines of a map_server YAML, and cells read from
/// the native-zoom raster tiles.

#include <gtest/gtest.h>
#include <png.h>

#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "client/http_client.h"

namespace rmap::testing {

struct GreyAlpha {
  int width = 0, height = 0;
  std::vector<uint8_t> pixels;  ///< grey, alpha per pixel, row 0 first
};

inline GreyAlpha decodePng(const std::string& png) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&image, png.data(), png.size())) throw std::runtime_error("not a PNG");
  image.format = PNG_FORMAT_GA;
  GreyAlpha out{static_cast<int>(image.width), static_cast<int>(image.height),
                std::vector<uint8_t>(PNG_IMAGE_SIZE(image))};
  if (!png_image_finish_read(&image, nullptr, out.pixels.data(), 0, nullptr)) throw std::runtime_error("bad PNG");
  return out;
}

/// "key: value" lines (a map_server YAML is one level deep).
inline std::map<std::string, std::string> parseYaml(const std::string& text) {
  std::map<std::string, std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    const size_t colon = line.find(": ");
    if (colon != std::string::npos) out[line.substr(0, colon)] = line.substr(colon + 2);
  }
  return out;
}

/// Cells of a layer read through native-zoom tiles (one cell per pixel), fetched once each.
class LayerCells {
 public:
  LayerCells(client::HttpClient& http, std::string map, std::string layer)
      : http_(http), prefix_("/v1/maps/" + std::move(map) + "/layers/" + std::move(layer) + "/8/") {}
  /// Grey and alpha of a cell.
  std::pair<uint8_t, uint8_t> at(int cx, int cy) {
    const int tx = (cx + 32768) >> 8, ty = (32767 - cy) >> 8;
    auto it = tiles_.find({tx, ty});
    if (it == tiles_.end()) {
      const client::HttpResponse r = http_.get(prefix_ + std::to_string(tx) + "/" + std::to_string(ty) + ".png");
      EXPECT_EQ(r.status, 200) << r.body;
      EXPECT_EQ(r.header("content-type"), "image/png");
      it = tiles_.emplace(std::pair{tx, ty}, decodePng(r.body)).first;
    }
    const size_t i = 2 * static_cast<size_t>(((32767 - cy) & 255) * 256 + ((cx + 32768) & 255));
    return {it->second.pixels[i], it->second.pixels[i + 1]};
  }

 private:
  client::HttpClient& http_;
  std::string prefix_;
  std::map<std::pair<int, int>, GreyAlpha> tiles_;
};

}  // namespace rmap::testing
