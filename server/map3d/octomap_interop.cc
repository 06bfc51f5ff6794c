#include "map3d/octomap_interop.h"

namespace rmap::map3d {

std::unique_ptr<CuboidMap> mapFromBt(const BtTree& tree, const OccupancyParams& occupancy, const FusionParams& fusion) {
  auto map = std::make_unique<CuboidMap>(tree.resolution_m, occupancy, fusion);
  std::vector<CuboidBox> boxes;
  boxes.reserve(tree.leaves.size());
  for (const BtLeaf& leaf : tree.leaves) {
    const int32_t last = leaf.size_cells - 1;
    boxes.push_back({leaf.min_cell,
                     {leaf.min_cell.x + last, leaf.min_cell.y + last, leaf.min_cell.z + last},
                     leaf.occupied ? occupancy.clamp_max_log_odds : occupancy.clamp_min_log_odds});
  }
  map->setCuboids(boxes);
  return map;
}

std::string mapToBt(const CuboidMap& map) {
  std::vector<BtCell> cells;
  const float threshold = map.occupancyParams().occupied_threshold_log_odds;
  map.forEachKnownCell([&](const CellKey& c, float log_odds) { cells.push_back({c, log_odds >= threshold}); });
  return writeBt(map.resolution(), std::move(cells));
}

}  // namespace rmap::map3d
