#pragma once
/// @file octomap_interop.h
/// Conversion between a CuboidMap and OctoMap's `.bt` trees (see octomap_bt.h).

#include <memory>
#include <string>

#include "map3d/cuboid_map.h"
#include "map3d/octomap_bt.h"

namespace rmap::map3d {

/// Builds a map at the tree's resolution: occupied leaves take the upper
/// clamp, free leaves the lower one, as OctoMap's readBinary does.
std::unique_ptr<CuboidMap> mapFromBt(const BtTree& tree, const OccupancyParams& occupancy = {},
                                     const FusionParams& fusion = {});

/// `.bt` bytes holding the maximum-likelihood state of every known cell.
std::string mapToBt(const CuboidMap& map);

}  // namespace rmap::map3d
