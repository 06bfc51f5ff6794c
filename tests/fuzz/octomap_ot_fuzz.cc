// Fuzz target: an `.ot` body of POST /v1/maps/{map}:import (app/map_transfer.cc):
// parsed and its leaves cut into the map's blocks within an import limit.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string_view>

#include "app/config.h"
#include "map3d/octomap_interop.h"

// The server's default limits.max_import_blocks (1,000,000) lets a 5 KiB tree fill 720,000
// blocks in seconds, which is allowed; a lower limit runs the same code with inputs in
// milliseconds, and the refusal past it as often.
constexpr uint64_t kMaxImportBlocks = 20'000;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const rmap::app::MapDefaults defaults;
  try {
    const rmap::map3d::OtTree tree = rmap::map3d::parseOt(bytes);
    rmap::map3d::blocksFromLeaves(tree.leaves, defaults.occupancy, defaults.fusion, kMaxImportBlocks);
  } catch (const std::runtime_error&) {  // not a tree
  } catch (const std::length_error&) {   // over the block limit: 413
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
