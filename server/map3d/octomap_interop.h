#pragma once
/// @file octomap_interop.h
/// Conversion between a CuboidMap and OctoMap's trees (`.bt`, see
/// octomap_bt.h; `.ot`, see octomap_ot.h).

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "map3d/cuboid_map.h"
#include "map3d/octomap_bt.h"
#include "map3d/octomap_ot.h"

namespace rmap::map3d {

/// Builds a map at the tree's resolution: occupied leaves take the upper
/// clamp, free leaves the lower one, as OctoMap's readBinary does.
std::unique_ptr<CuboidMap> mapFromBt(const BtTree& tree, const OccupancyParams& occupancy = {},
                                     const FusionParams& fusion = {});

/// `.bt` bytes holding the maximum-likelihood state of every known cell.
std::string mapToBt(const CuboidMap& map);

/// The leaves of a `.bt` tree with log-odds: the upper clamp for occupied
/// leaves, the lower one for free leaves (as mapFromBt).
std::vector<OctreeLeaf> leavesOf(const BtTree& tree, const OccupancyParams& occupancy);

/// A map's content in storage form: fused cuboids per block, the input of
/// CuboidMap::replaceBlocks.
using MapBlocks = std::vector<std::pair<BlockKey, std::vector<PackedCuboid>>>;

/// Cuts disjoint octree leaves into blocks: a leaf of 16 cells or more fills
/// whole blocks with one cuboid each, a smaller one is a cuboid inside its
/// block; blocks holding several leaves are fused as the map fuses its own.
/// Log-odds are clamped to `occupancy`'s clamps. Memory is a few bytes per
/// cuboid: no block is expanded beyond one at a time.
/// @param max_blocks  the most blocks the leaves may fill (a leaf near the
///        root of a tree covers billions of cells)
/// @throws std::length_error naming the count when the leaves fill more than
///         max_blocks blocks (checked before anything is allocated for them)
/// @throws std::invalid_argument for a leaf outside the addressable range,
///         of a size that is not a power of two or not aligned to it
MapBlocks blocksFromLeaves(std::span<const OctreeLeaf> leaves, const OccupancyParams& occupancy,
                           const FusionParams& fusion, uint64_t max_blocks);

}  // namespace rmap::map3d
