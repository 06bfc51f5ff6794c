#include "slam2d/probability_raster.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace rmap::slam2d {

namespace {

void checkUnknown(float unknown_p) {
  if (!(unknown_p >= 0.0f && unknown_p <= 1.0f))
    throw std::invalid_argument("probability raster: unknown_p must be in [0, 1], got " + std::to_string(unknown_p));
}

}  // namespace

void ProbabilityRaster::validate() const {
  if (!(resolution_m > 0.0) || !std::isfinite(resolution_m))
    throw std::invalid_argument("probability raster: resolution_m must be finite and > 0");
  if (!origin_m.allFinite()) throw std::invalid_argument("probability raster: origin_m must be finite");
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("probability raster: width and height must be > 0, got " + std::to_string(width) +
                                " x " + std::to_string(height));
  if (p.size() != static_cast<size_t>(width) * static_cast<size_t>(height))
    throw std::invalid_argument("probability raster: p holds " + std::to_string(p.size()) + " values for " +
                                std::to_string(width) + " x " + std::to_string(height) + " cells");
  for (size_t i = 0; i < p.size(); ++i)
    if (!(p[i] >= 0.0f && p[i] <= 1.0f))
      throw std::invalid_argument("probability raster: p[" + std::to_string(i) + "] is not in [0, 1]");
  if (!(outside_p >= 0.0f && outside_p <= 1.0f))
    throw std::invalid_argument("probability raster: outside_p must be in [0, 1]");
}

ProbabilityRaster rasterFromGrid(const OccupancyGrid& grid, const Eigen::AlignedBox2i& cells, float unknown_p) {
  checkUnknown(unknown_p);
  if (cells.isEmpty()) throw std::invalid_argument("rasterFromGrid: empty cell box");
  const Eigen::Vector2i size = cells.max() - cells.min() + Eigen::Vector2i::Ones();
  if (static_cast<int64_t>(size.x()) * size.y() > (int64_t{1} << 30))
    throw std::invalid_argument("rasterFromGrid: box of " + std::to_string(size.x()) + " x " +
                                std::to_string(size.y()) + " cells is too large");
  ProbabilityRaster raster;
  raster.resolution_m = grid.resolution_m();
  raster.origin_m = cells.min().cast<double>() * grid.resolution_m();
  raster.width = size.x();
  raster.height = size.y();
  raster.outside_p = unknown_p;
  raster.p.resize(static_cast<size_t>(size.x()) * static_cast<size_t>(size.y()));
  for (int y = 0; y < size.y(); ++y)
    for (int x = 0; x < size.x(); ++x) {
      const float p = grid.probability(cells.min() + Eigen::Vector2i(x, y));
      raster.p[static_cast<size_t>(y) * static_cast<size_t>(size.x()) + static_cast<size_t>(x)] =
          std::isnan(p) ? unknown_p : p;
    }
  return raster;
}

ProbabilityRaster maxFiltered(const ProbabilityRaster& raster, int radius_cells) {
  if (radius_cells < 0) throw std::invalid_argument("maxFiltered: radius_cells must be ≥ 0");
  ProbabilityRaster out = raster;
  if (radius_cells == 0) return out;
  const auto at = [](const std::vector<float>& v, int width, int x, int y) -> float {
    return v[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)];
  };
  // Separable: rows into `rows`, then columns of `rows` into out.p.
  std::vector<float> rows(raster.p.size());
  for (int y = 0; y < raster.height; ++y)
    for (int x = 0; x < raster.width; ++x) {
      float m = at(raster.p, raster.width, x, y);
      for (int i = std::max(0, x - radius_cells); i <= std::min(raster.width - 1, x + radius_cells); ++i)
        m = std::max(m, at(raster.p, raster.width, i, y));
      rows[static_cast<size_t>(y) * static_cast<size_t>(raster.width) + static_cast<size_t>(x)] = m;
    }
  for (int y = 0; y < raster.height; ++y)
    for (int x = 0; x < raster.width; ++x) {
      float m = at(rows, raster.width, x, y);
      for (int j = std::max(0, y - radius_cells); j <= std::min(raster.height - 1, y + radius_cells); ++j)
        m = std::max(m, at(rows, raster.width, x, j));
      out.p[static_cast<size_t>(y) * static_cast<size_t>(raster.width) + static_cast<size_t>(x)] = m;
    }
  return out;
}

ProbabilityRaster rasterFromScans(std::span<const PosedScan> scans, double resolution_m, float unknown_p,
                                  const OccupancyUpdate& update, double max_ray_m, int margin_cells) {
  checkUnknown(unknown_p);
  if (!(resolution_m > 0.0) || !std::isfinite(resolution_m))
    throw std::invalid_argument("rasterFromScans: resolution_m must be finite and > 0");
  if (margin_cells < 0) throw std::invalid_argument("rasterFromScans: margin_cells must be ≥ 0");
  if (!(max_ray_m > 0.0)) throw std::invalid_argument("rasterFromScans: max_ray_m must be > 0");
  for (const PosedScan& scan : scans) {
    if (!scan.pose.isFinite()) throw std::invalid_argument("rasterFromScans: a pose is not finite");
    for (const Eigen::Vector2d& p : scan.points_robot)
      if (!p.allFinite()) throw std::invalid_argument("rasterFromScans: a point is not finite");
  }
  OccupancyGrid grid(resolution_m);
  std::vector<Ray> rays;
  for (const PosedScan& scan : scans) {
    rays.clear();
    for (const Eigen::Vector2d& p : scan.points_robot) rays.push_back({scan.pose * p, true});
    grid.insert(scan.pose.translation(), rays, update, max_ray_m);
  }
  if (grid.knownCells().isEmpty()) throw std::invalid_argument("rasterFromScans: the scans observed no cell");
  Eigen::AlignedBox2i box = grid.knownCells();
  box.min().array() -= margin_cells;
  box.max().array() += margin_cells;
  return rasterFromGrid(grid, box, unknown_p);
}

}  // namespace rmap::slam2d
