#pragma once
/// @file memory_bound.h
/// rmapd's resident memory against `limits.max_memory_bytes`. While the
/// process holds more, robot data and map imports are refused before anything
/// is stored (the sender resends later); queries and viewers go on. The bound
/// is soft: what was accepted before a sample crossed it is still stored and
/// applied, so the overshoot is at most the messages in flight then.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

namespace rmap::app {

/// Resident set of this process (bytes, /proc/self/statm); 0 where it cannot be read.
uint64_t residentBytes();
/// Peak resident set of this process (bytes): the larger of VmHWM (/proc/self/status)
/// and every residentBytes() so far; Linux updates VmHWM lazily, so it alone can
/// miss a peak that was sampled. 0 where neither can be read.
uint64_t peakResidentBytes();
/// Hands freed heap pages back to the system (glibc keeps them resident otherwise,
/// so the resident size would not fall below the bound after a spike).
void releaseFreeHeap();

class MemoryBound {
 public:
  using Sampler = std::function<uint64_t()>;
  using Release = std::function<void()>;

  /// @param max_bytes  0 = no bound
  /// @param period     a sample younger than this is reused (reading /proc costs a few µs)
  /// @param release    run (then sampled again) when a sample is above the bound,
  ///                   at most once per second
  explicit MemoryBound(uint64_t max_bytes, Sampler sampler = residentBytes, Release release = releaseFreeHeap,
                       std::chrono::nanoseconds period = std::chrono::milliseconds(10));

  uint64_t maxBytes() const { return max_bytes_; }
  /// Whether the latest sample is above the bound (false without one). Thread-safe;
  /// one caller at a time takes a new sample, the others read the latest.
  bool exceeded();
  /// "the server is above its memory bound of N MiB", for refusals.
  std::string describe() const;

 private:
  const uint64_t max_bytes_;
  const Sampler sampler_;
  const Release release_;
  const int64_t period_ns_;
  std::atomic<int64_t> sampled_at_ns_;
  std::atomic<int64_t> released_at_ns_;
  std::atomic<uint64_t> resident_bytes_{0};
};

}  // namespace rmap::app
