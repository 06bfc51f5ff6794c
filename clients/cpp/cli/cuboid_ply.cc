#include "cli/cuboid_ply.h"

#include <bit>
#include <cstdint>
#include <cstring>

namespace rmap::cli {

namespace {

static_assert(std::endian::native == std::endian::little, "the PLY writer emits the host's byte order");

template <typename T>
void append(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

/// Corner k of a cuboid: bit 0 of k picks max x, bit 1 max y, bit 2 max z.
std::array<float, 3> corner(const Cuboid& c, int k) {
  std::array<float, 3> p;
  for (int a = 0; a < 3; ++a) p[a] = static_cast<float>(((k >> a) & 1) ? c.max_m[a] : c.min_m[a]);
  return p;
}

/// Faces of a box over the corners above, counter-clockwise seen from outside:
/// −z, +z, −y, +y, −x, +x.
constexpr int kFaces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

/// @param elements  the element lines and their properties, e.g. "element vertex 8\nproperty float x\n…"
std::string header(const std::string& elements) {
  return "ply\nformat binary_little_endian 1.0\ncomment rmap cuboids, metres, map frame\n" + elements +
         "end_header\n";
}

}  // namespace

std::string cuboidCentresPly(std::span<const Cuboid> cuboids) {
  std::string out = header("element vertex " + std::to_string(cuboids.size()) +
                           "\nproperty float x\nproperty float y\nproperty float z\nproperty float size_x\n"
                           "property float size_y\nproperty float size_z\nproperty float probability\n");
  out.reserve(out.size() + cuboids.size() * 7 * sizeof(float));
  for (const Cuboid& c : cuboids) {
    for (int a = 0; a < 3; ++a) append(out, static_cast<float>((c.min_m[a] + c.max_m[a]) / 2));
    for (int a = 0; a < 3; ++a) append(out, static_cast<float>(c.max_m[a] - c.min_m[a]));
    append(out, c.probability);
  }
  return out;
}

std::string cuboidMeshPly(std::span<const Cuboid> cuboids) {
  std::string out = header("element vertex " + std::to_string(8 * cuboids.size()) +
                           "\nproperty float x\nproperty float y\nproperty float z\nproperty float probability\n"
                           "element face " +
                           std::to_string(6 * cuboids.size()) + "\nproperty list uchar int vertex_indices\n");
  out.reserve(out.size() + cuboids.size() * (8 * 4 * sizeof(float) + 6 * (1 + 4 * sizeof(int32_t))));
  for (const Cuboid& c : cuboids) {
    for (int k = 0; k < 8; ++k) {
      for (float v : corner(c, k)) append(out, v);
      append(out, c.probability);
    }
  }
  for (size_t i = 0; i < cuboids.size(); ++i) {
    const auto first = static_cast<int32_t>(8 * i);
    for (const auto& face : kFaces) {
      append(out, uint8_t{4});
      for (int k : face) append(out, first + k);
    }
  }
  return out;
}

}  // namespace rmap::cli
