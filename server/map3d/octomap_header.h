#pragma once
/// @file octomap_header.h
/// The text header OctoMap writes before a tree, in `.bt` and `.ot` files
/// alike (AbstractOcTree::readHeader): a first line that names the format,
/// then whitespace-separated keywords `id <type>`, `size <nodes>`,
/// `res <metres>`, and `data`, whose line ends the header. `#…` comments and
/// unknown keywords skip the rest of their line.

#include <cstdint>
#include <string>
#include <string_view>

namespace rmap::map3d {

/// OctoMap's trees have 16 levels: a node at depth d is a cube of 2^(16-d) base cells.
inline constexpr int kOctreeDepth = 16;
/// OctoMap key of cell index 0 (CellKey = key − 32768).
inline constexpr int32_t kOctreeKeyOffset = 32768;

struct OctreeHeader {
  std::string id;             ///< tree type, e.g. "OcTree", "ColorOcTree"; empty when absent
  double resolution_m = 0.0;  ///< finite and > 0
  uint64_t size = 0;          ///< nodes in the tree
  size_t data_offset = 0;     ///< first byte of the tree
};

/// @param magic   the prefix the first line must have (OctoMap compares only that)
/// @param format  names the format in messages, e.g. "OctoMap .bt"
/// @throws std::runtime_error "<format>: …" naming the problem (bad first line,
///         no data line, bad or missing size or res)
OctreeHeader readOctreeHeader(std::string_view bytes, std::string_view magic, const std::string& format);

/// Whether the header announces an empty tree, which OctoMap writes as `size 0` and no data.
/// @throws std::runtime_error "<format>: …" when data follows such a header
bool isEmptyTree(const OctreeHeader& header, std::string_view data, const std::string& format);

/// Checks that the tree read from the data ended with it and has the header's node count.
/// @throws std::runtime_error "<format>: …" for trailing bytes or another node count
void checkTreeEnd(const OctreeHeader& header, std::string_view data, size_t bytes_read, uint64_t nodes_read,
                  const std::string& format);

}  // namespace rmap::map3d
