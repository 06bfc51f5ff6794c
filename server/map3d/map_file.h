#pragma once
/// @file map_file.h
/// rmap's own compact map format (`.rmap`): the fused cuboids of every block
/// and the map's parameters, little-endian, protected by a CRC-32.
///
/// Layout: "RMAPCUB" 0x00, u32 format version (1), f64 resolution_m,
/// f32 hit, miss, clamp_min, clamp_max, occupied_threshold (log-odds),
/// u8 sensor model, f64 max_range_m, f32 fusion tolerance, i32 fuse_after_scans,
/// u64 block count, then per block i32 x y z, u32 n, n × (u16 lo, u16 hi,
/// f32 log_odds); last a u32 CRC-32 of all bytes before it.
/// About 8 bytes per cuboid plus 16 per block.

#include <memory>
#include <string>
#include <string_view>

#include "map3d/cuboid_map.h"

namespace rmap::map3d {

/// Serialises the map (hot blocks are written fused, the map is not changed).
std::string encodeMap(const CuboidMap& map);

/// Rebuilds a map from encodeMap's bytes.
/// @throws std::runtime_error naming the problem (bad magic, unsupported
///         version, truncated, CRC mismatch, invalid parameters or cuboids)
std::unique_ptr<CuboidMap> decodeMap(std::string_view bytes);

}  // namespace rmap::map3d
