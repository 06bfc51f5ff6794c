#pragma once
/// @file cuboid_ply.h
/// Cuboids of a map as PLY (binary little-endian, version 1.0), for point
/// cloud and mesh tools (CloudCompare, MeshLab, Open3D, Blender).

#include <array>
#include <span>
#include <string>

namespace rmap::cli {

/// A cuboid as the box query answers it (docs/API.md §6.7).
struct Cuboid {
  std::array<double, 3> min_m{};  ///< lower corner, map frame
  std::array<double, 3> max_m{};  ///< upper corner (the cells' upper edges)
  float probability = 0.5f;       ///< occupancy probability
};

/// One vertex per cuboid at its centre: float x, y, z (m), size_x, size_y,
/// size_z (m, the edges) and probability.
std::string cuboidCentresPly(std::span<const Cuboid> cuboids);

/// Each cuboid as a closed box: 8 vertices (float x, y, z, probability) and
/// 6 quad faces (`vertex_indices`, uchar count and int indices), wound
/// counter-clockwise seen from outside, so normals point out of the box.
std::string cuboidMeshPly(std::span<const Cuboid> cuboids);

}  // namespace rmap::cli
