// Fuzz target: the bytes of an OctoMap scan graph (datasets/octomap_graph.h).
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string_view>

#include "datasets/octomap_graph.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    rmap::datasets::parseOctomapGraph(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.graph");
  } catch (const std::runtime_error&) {
  }
  return 0;
}
