#include "app/memory_bound.h"

#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>

namespace rmap::app {

namespace {

constexpr int64_t kReleasePeriod_ns = 1'000'000'000;
/// Older than any sample or release: the first call takes one.
constexpr int64_t kNever_ns = std::numeric_limits<int64_t>::min() / 2;

int64_t steadyNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

/// The largest resident size residentBytes() returned.
std::atomic<uint64_t> largest_sample_bytes{0};

}  // namespace

uint64_t residentBytes() {
  std::FILE* file = std::fopen("/proc/self/statm", "r");
  if (!file) return 0;
  unsigned long long size_pages = 0, resident_pages = 0;
  const int read = std::fscanf(file, "%llu %llu", &size_pages, &resident_pages);
  std::fclose(file);
  const uint64_t bytes = read == 2 ? resident_pages * static_cast<uint64_t>(::sysconf(_SC_PAGESIZE)) : 0;
  uint64_t largest = largest_sample_bytes.load(std::memory_order_relaxed);
  while (bytes > largest && !largest_sample_bytes.compare_exchange_weak(largest, bytes, std::memory_order_relaxed)) {
  }
  return bytes;
}

uint64_t peakResidentBytes() {
  uint64_t high_water = 0;
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmHWM:", 0) == 0) high_water = std::stoull(line.substr(6)) * 1024;  // "VmHWM:   123456 kB"
  }
  return std::max(high_water, largest_sample_bytes.load(std::memory_order_relaxed));
}

void releaseFreeHeap() { ::malloc_trim(0); }

MemoryBound::MemoryBound(uint64_t max_bytes, Sampler sampler, Release release, std::chrono::nanoseconds period)
    : max_bytes_(max_bytes),
      sampler_(std::move(sampler)),
      release_(std::move(release)),
      period_ns_(period.count()),
      sampled_at_ns_(kNever_ns),
      released_at_ns_(kNever_ns) {}

bool MemoryBound::exceeded() {
  if (max_bytes_ == 0) return false;
  const int64_t now = steadyNs();
  int64_t sampled_at = sampled_at_ns_.load(std::memory_order_acquire);
  if (now - sampled_at >= period_ns_ && sampled_at_ns_.compare_exchange_strong(sampled_at, now)) {
    uint64_t resident = sampler_();
    if (resident > max_bytes_ && now - released_at_ns_.load(std::memory_order_relaxed) >= kReleasePeriod_ns) {
      released_at_ns_.store(now, std::memory_order_relaxed);
      release_();
      resident = sampler_();
    }
    resident_bytes_.store(resident, std::memory_order_release);
  }
  return resident_bytes_.load(std::memory_order_acquire) > max_bytes_;
}

std::string MemoryBound::describe() const {
  char text[96];
  std::snprintf(text, sizeof text, "the server is above its memory bound of %.4g MiB",
                static_cast<double>(max_bytes_) / (1 << 20));
  return text;
}

}  // namespace rmap::app
