#pragma once
/// @file octomap_ot.h
/// Reader of OctoMap's full-probability format (`.ot`, AbstractOcTree::write,
/// OctoMap 1.9.x): the header of octomap_header.h with the first line
/// `# Octomap OcTree file`, then the tree depth-first. Each node is its data
/// — a float log-odds (`OcTree`), followed by 3 colour bytes (`ColorOcTree`)
/// or a uint32 timestamp (`OcTreeStamped`) — then one byte with bit i set when
/// child i exists, then those children. Child i lies at +x when bit 0 of i is
/// set, +y for bit 1, +z for bit 2. Nodes without children are the leaves;
/// space under an inner node that has no child there is unknown.
/// Pure in-memory code: callers read the files.

#include <string>
#include <string_view>
#include <vector>

#include "map3d/cell_key.h"

namespace rmap::map3d {

/// A leaf of an octree with its occupancy: a cube of base cells.
struct OctreeLeaf {
  CellKey min_cell;    ///< lowest cell index of the cube (CellKey convention, OctoMap key − 32768)
  int32_t size_cells;  ///< edge of the cube in base cells, a power of two in [1, 65536]
  float log_odds;      ///< finite
};

struct OtTree {
  std::string id;                 ///< "OcTree", "ColorOcTree" or "OcTreeStamped"
  double resolution_m = 0.0;      ///< base cell edge from the `res` header line
  std::vector<OctreeLeaf> leaves;  ///< in depth-first file order
};

/// Whether `bytes` start with the `.ot` first line.
bool looksLikeOt(std::string_view bytes);

/// Parses `.ot` bytes.
/// @throws std::runtime_error naming the problem (bad first line, unsupported
///         id, bad size/res, truncated data, a node below depth 16, a leaf
///         whose log-odds is not finite, trailing bytes, node count different
///         from `size`)
OtTree parseOt(std::string_view bytes);

}  // namespace rmap::map3d
