#pragma once
/// @file wall_clock.h
/// The server's wall clock, as it stamps what it records (receipts, events, sessions).

#include <chrono>
#include <cstdint>

namespace rmap::app {

/// Nanoseconds since the Unix epoch by the system clock.
inline int64_t nowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace rmap::app
