// Fuzz target: PLY content (datasets/ply_cloud.h); every scalar column must
// have one value per vertex.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string_view>

#include "datasets/ply_cloud.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  rmap::datasets::PlyCloud cloud;
  try {
    cloud = rmap::datasets::parsePlyCloud(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.ply");
  } catch (const std::runtime_error&) {
    return 0;
  }
  for (const auto& [name, values] : cloud.scalars) {
    if (values.size() != cloud.points_m.size()) __builtin_trap();
  }
  return 0;
}
