#include "slam2d/grid_map.h"

#include <stdexcept>
#include <string>

namespace rmap::slam2d {

namespace {
std::vector<OccupancyGrid> makeLevels(double resolution_m, int levels) {
  if (levels < 1 || levels > 16)
    throw std::invalid_argument("GridMap2d: levels must be in [1, 16], got " + std::to_string(levels));
  std::vector<OccupancyGrid> grids;
  grids.reserve(static_cast<size_t>(levels));
  for (int i = 0; i < levels; ++i) grids.emplace_back(resolution_m * static_cast<double>(1 << i));
  return grids;
}
}  // namespace

GridMap2d::GridMap2d(double resolution_m, int levels)
    : levels_(makeLevels(resolution_m, levels)), reflectivity_(resolution_m) {}

void GridMap2d::insert(const Eigen::Vector2d& origin_m, std::span<const Ray> rays, const OccupancyUpdate& update,
                       double max_ray_m) {
  for (OccupancyGrid& grid : levels_) grid.insert(origin_m, rays, update, max_ray_m);
}

}  // namespace rmap::slam2d
