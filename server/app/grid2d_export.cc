#include "app/grid2d_export.h"

#include <charconv>
#include <cmath>
#include <vector>

#include "app/image_codecs.h"

namespace rmap::app {

namespace {

/// Shortest text that reads back as the same double.
std::string number(double v) {
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof(buffer), v).ptr;
  return std::string(buffer, end);
}

}  // namespace

uint8_t pgmValue(float probability) {
  if (probability >= kOccupiedThresh) return kPgmOccupied;
  if (probability <= kFreeThresh) return kPgmFree;
  return kPgmUnknown;  // also NaN
}

std::string exportGridPgm(const Grid2dSource& grid) {
  const Eigen::AlignedBox2i known = grid.knownCells();
  if (known.isEmpty()) return encodePgm(1, 1, std::vector<uint8_t>{kPgmUnknown});
  const int width = known.max().x() - known.min().x() + 1;
  const int height = known.max().y() - known.min().y() + 1;
  std::vector<uint8_t> pixels(static_cast<size_t>(width) * static_cast<size_t>(height));
  size_t i = 0;
  for (int y = known.max().y(); y >= known.min().y(); --y) {
    for (int x = known.min().x(); x <= known.max().x(); ++x) pixels[i++] = pgmValue(grid.probability({x, y}));
  }
  return encodePgm(width, height, pixels);
}

std::string exportGridYaml(const Grid2dSource& grid, const std::string& image) {
  const Eigen::AlignedBox2i known = grid.knownCells();
  const double r = grid.resolutionM();
  const Eigen::Vector2d origin =
      known.isEmpty() ? Eigen::Vector2d(Eigen::Vector2d::Zero()) : Eigen::Vector2d(known.min().cast<double>() * r);
  return "image: " + image + "\nresolution: " + number(r) + "\norigin: [" + number(origin.x()) + ", " +
         number(origin.y()) + ", 0.0]\nnegate: 0\noccupied_thresh: " + number(kOccupiedThresh) +
         "\nfree_thresh: " + number(kFreeThresh) + "\nmode: trinary\n";
}

}  // namespace rmap::app
