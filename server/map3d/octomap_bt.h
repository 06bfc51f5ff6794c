#pragma once
/// @file octomap_bt.h
/// Codec for OctoMap's binary tree format (`.bt`, OctoMap 1.9.x `OcTree`).
///
/// The format holds only maximum-likelihood states: a header of text lines
/// (`# Octomap OcTree binary file`, optional comments, `id OcTree`, `size N`,
/// `res R`, `data`) followed by the tree depth-first, 2 bytes per inner node
/// (2 bits per child: 01 occupied leaf, 10 free leaf, 11 inner node, 00 unknown).
/// The tree has 16 levels; a leaf at depth d is a cube of 2^(16-d) base cells.
/// Pure in-memory code: callers read and write the files.

#include <string>
#include <string_view>
#include <vector>

#include "map3d/cell_key.h"

namespace rmap::map3d {

/// A leaf of the tree: an axis-aligned cube of base cells.
struct BtLeaf {
  CellKey min_cell;     ///< lowest cell index of the cube (CellKey convention, OctoMap key − 32768)
  int32_t size_cells;   ///< edge of the cube in base cells, a power of two in [1, 65536]
  bool occupied;        ///< true: occupied leaf; false: free leaf
};

struct BtTree {
  double resolution_m = 0.0;   ///< base cell edge from the `res` header line
  std::vector<BtLeaf> leaves;  ///< in depth-first file order
};

/// A base cell with its state, input of writeBt.
struct BtCell {
  CellKey cell;
  bool occupied;
};

/// Whether `bytes` start with the `.bt` first line.
bool looksLikeBt(std::string_view bytes);

/// Parses `.bt` bytes.
/// @throws std::runtime_error with a message naming the problem (bad magic,
///         unsupported id, bad size/res, truncated data, trailing bytes, node
///         count different from `size`).
BtTree parseBt(std::string_view bytes);

/// Serialises base cells as a `.bt` tree that OctoMap 1.9.7 reads back with
/// the same occupied/free cells. Octants whose cells are all known with the
/// same state are written as one pruned leaf, as OctoMap itself would.
/// Duplicate cells: the last one wins.
/// @param resolution_m  base cell edge, > 0
/// @throws std::invalid_argument for a cell outside [-32768, 32768) or a bad resolution
std::string writeBt(double resolution_m, std::vector<BtCell> cells);

/// As writeBt, from disjoint cubes given as leaves (aligned to their edge, a
/// power of two of at most 32768 cells), e.g. cuboids cut into octants: 8
/// bytes of memory per cube rather than per cell. Cubes must not overlap.
/// @throws std::invalid_argument for a cube that is not aligned, too large,
///         outside the addressable range, or a bad resolution
std::string writeBtCubes(double resolution_m, const std::vector<BtLeaf>& cubes);

}  // namespace rmap::map3d
