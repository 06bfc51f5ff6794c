#include "map3d/octomap_interop.h"

#include <algorithm>
#include <bit>
#include <stdexcept>
#include <unordered_map>

#include "map3d/fusion.h"

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

namespace {

/// Appends the cubes of the octree under the cube at `origin` (edge `size`, aligned) that lie
/// inside `box`, each as large as it can be.
void appendCubes(const CuboidBox& box, const CellKey& origin, int32_t size, bool occupied, std::vector<BtLeaf>& out) {
  bool inside = true;
  for (int a = 0; a < 3; ++a) {
    if (origin[a] > box.max[a] || origin[a] + size - 1 < box.min[a]) return;
    inside = inside && origin[a] >= box.min[a] && origin[a] + size - 1 <= box.max[a];
  }
  if (inside) {
    out.push_back({origin, size, occupied});
    return;
  }
  const int32_t half = size / 2;
  for (int i = 0; i < 8; ++i) {
    appendCubes(box, {origin.x + ((i & 1) ? half : 0), origin.y + ((i & 2) ? half : 0), origin.z + ((i & 4) ? half : 0)},
                half, occupied, out);
  }
}

}  // namespace

std::string mapToBt(const CuboidMap& map) {
  // Cuboids cut into octants, not cells: memory follows the tree's leaves, not the known volume.
  std::vector<BtLeaf> cubes;
  const float threshold = map.occupancyParams().occupied_threshold_log_odds;
  map.forEachBlock([&](const BlockView& view) {
    const CellKey origin{view.key.x << kBlockShift, view.key.y << kBlockShift, view.key.z << kBlockShift};
    for (const PackedCuboid& c : view.cuboids) {
      const CuboidBox box{{origin.x + c.lo(0), origin.y + c.lo(1), origin.z + c.lo(2)},
                          {origin.x + c.hi(0), origin.y + c.hi(1), origin.z + c.hi(2)},
                          c.log_odds};
      appendCubes(box, origin, kBlockEdge, c.log_odds >= threshold, cubes);
    }
  });
  return writeBtCubes(map.resolution(), cubes);
}

std::vector<OctreeLeaf> leavesOf(const BtTree& tree, const OccupancyParams& occupancy) {
  std::vector<OctreeLeaf> out;
  out.reserve(tree.leaves.size());
  for (const BtLeaf& leaf : tree.leaves) {
    out.push_back({leaf.min_cell, leaf.size_cells,
                   leaf.occupied ? occupancy.clamp_max_log_odds : occupancy.clamp_min_log_odds});
  }
  return out;
}

MapBlocks blocksFromLeaves(std::span<const OctreeLeaf> leaves, const OccupancyParams& occupancy,
                           const FusionParams& fusion, uint64_t max_blocks) {
  // Count first: one leaf may cover more blocks than memory holds.
  uint64_t upper_bound = 0;
  for (const OctreeLeaf& leaf : leaves) {
    const int32_t s = leaf.size_cells;
    const CellKey last{leaf.min_cell.x + s - 1, leaf.min_cell.y + s - 1, leaf.min_cell.z + s - 1};
    // Aligned in OctoMap's key space, where the tree's cubes start at multiples of their size.
    const auto aligned = [&](int32_t cell) { return s > 0 && (cell + kCellLimit) % s == 0; };
    if (s < 1 || s > 2 * kCellLimit || !std::has_single_bit(static_cast<uint32_t>(s)) ||
        !aligned(leaf.min_cell.x) || !aligned(leaf.min_cell.y) || !aligned(leaf.min_cell.z) ||
        !cellInRange(leaf.min_cell) || !cellInRange(last)) {
      throw std::invalid_argument("octree leaf at cell (" + std::to_string(leaf.min_cell.x) + ", " +
                                  std::to_string(leaf.min_cell.y) + ", " + std::to_string(leaf.min_cell.z) +
                                  ") of size " + std::to_string(s) +
                                  " is not an aligned power-of-two cube inside the addressable range");
    }
    const uint64_t per_axis = s >= kBlockEdge ? static_cast<uint64_t>(s / kBlockEdge) : 1;
    upper_bound += per_axis * per_axis * per_axis;
  }
  if (upper_bound > max_blocks) {
    throw std::length_error("the octree fills " + std::to_string(upper_bound) + " blocks of 16³ cells, more than the " +
                            std::to_string(max_blocks) + " allowed");
  }
  const float lo = occupancy.clamp_min_log_odds, hi = occupancy.clamp_max_log_odds;
  std::unordered_map<BlockKey, std::vector<PackedCuboid>, BlockKeyHash> blocks;
  blocks.reserve(static_cast<size_t>(upper_bound));
  constexpr int m = kBlockEdge - 1;
  for (const OctreeLeaf& leaf : leaves) {
    const float v = std::clamp(leaf.log_odds, lo, hi);
    const int32_t s = leaf.size_cells;
    if (s >= kBlockEdge) {
      const BlockKey first = blockOf(leaf.min_cell);
      const int32_t n = s / kBlockEdge;
      const PackedCuboid whole{PackedCuboid::pack(0, 0, 0), PackedCuboid::pack(m, m, m), v};
      for (int32_t z = 0; z < n; ++z) {
        for (int32_t y = 0; y < n; ++y) {
          for (int32_t x = 0; x < n; ++x) blocks[{first.x + x, first.y + y, first.z + z}].push_back(whole);
        }
      }
    } else {
      const CellKey& c = leaf.min_cell;
      blocks[blockOf(c)].push_back({PackedCuboid::pack(c.x & m, c.y & m, c.z & m),
                                    PackedCuboid::pack((c.x & m) + s - 1, (c.y & m) + s - 1, (c.z & m) + s - 1), v});
    }
  }
  MapBlocks out;
  out.reserve(blocks.size());
  DenseCells cells;
  for (auto& [key, cuboids] : blocks) {
    if (cuboids.size() > 1) {
      cells.known = BlockBits{};
      expandCuboids(cuboids, cells);
      cuboids = fuseBlock(cells, fusion.tolerance_log_odds, occupancy.occupied_threshold_log_odds);
    }
    out.emplace_back(key, std::move(cuboids));
  }
  return out;
}

}  // namespace rmap::map3d
