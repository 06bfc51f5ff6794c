// Fuzz target: the text of a CARMEN log (datasets/carmen_log.h) as `rmap replay`
// reads it: parsed, then its odometry checked for restarts at the scans and,
// when it restarts, turned into increments.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string_view>

#include "datasets/carmen_log.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  rmap::datasets::CarmenLog log;
  try {
    log = rmap::datasets::parseCarmenLog(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.log");
  } catch (const std::runtime_error&) {
    return 0;
  }
  if (rmap::datasets::odometryRestartsAtScans(log)) rmap::datasets::odometryFromOdomIncrements(log);
  return 0;
}
