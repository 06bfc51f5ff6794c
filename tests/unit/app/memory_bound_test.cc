#include "app/memory_bound.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstring>
#include <memory>
#include <thread>
#include <vector>

namespace rmap::app {
namespace {

using std::chrono::milliseconds;

/// A resident size the test sets, counting the samples and releases the bound takes.
struct FakeProcess {
  uint64_t resident_bytes = 0;
  uint64_t freed_by_release = 0;  ///< what a release hands back
  int samples = 0;
  int releases = 0;

  MemoryBound bound(uint64_t max_bytes, milliseconds period = milliseconds(0)) {
    return MemoryBound(
        max_bytes,
        [this] {
          ++samples;
          return resident_bytes;
        },
        [this] {
          ++releases;
          resident_bytes -= freed_by_release;
        },
        period);
  }
};

TEST(MemoryBound, WithoutABoundNothingIsEverSampled) {
  FakeProcess process;
  process.resident_bytes = uint64_t{1} << 40;
  MemoryBound bound = process.bound(0);
  EXPECT_FALSE(bound.exceeded());
  EXPECT_EQ(process.samples, 0);
}

TEST(MemoryBound, AboveTheBoundIsExceededAndBelowItResumes) {
  FakeProcess process;
  process.resident_bytes = 100;
  MemoryBound bound = process.bound(100);
  EXPECT_FALSE(bound.exceeded()) << "at the bound is not above it";
  process.resident_bytes = 101;
  EXPECT_TRUE(bound.exceeded());
  EXPECT_EQ(process.releases, 1) << "freed heap is handed back before refusing";
  process.resident_bytes = 60;
  EXPECT_FALSE(bound.exceeded());
}

TEST(MemoryBound, AReleaseThatFreesEnoughRefusesNothing) {
  FakeProcess process;
  process.resident_bytes = 150;
  process.freed_by_release = 80;
  MemoryBound bound = process.bound(100);
  EXPECT_FALSE(bound.exceeded());
  EXPECT_EQ(process.releases, 1);
  EXPECT_EQ(process.samples, 2) << "sampled again after the release";
}

TEST(MemoryBound, ReleasesAtMostOncePerSecond) {
  FakeProcess process;
  process.resident_bytes = 200;
  MemoryBound bound = process.bound(100);
  for (int i = 0; i < 50; ++i) EXPECT_TRUE(bound.exceeded());
  EXPECT_EQ(process.releases, 1);
  EXPECT_EQ(process.samples, 51) << "50 samples and the one after the release";
}

TEST(MemoryBound, ASampleIsReusedWithinItsPeriod) {
  FakeProcess process;
  process.resident_bytes = 10;
  MemoryBound bound = process.bound(100, milliseconds(200));
  EXPECT_FALSE(bound.exceeded());
  process.resident_bytes = 1000;
  EXPECT_FALSE(bound.exceeded()) << "the sample of 10 bytes is still fresh";
  EXPECT_EQ(process.samples, 1);
  std::this_thread::sleep_for(milliseconds(250));
  EXPECT_TRUE(bound.exceeded());
}

TEST(MemoryBound, DescribesTheBoundInMiB) {
  FakeProcess process;
  EXPECT_EQ(process.bound(512u << 20).describe(), "the server is above its memory bound of 512 MiB");
  EXPECT_EQ(process.bound(3u << 19).describe(), "the server is above its memory bound of 1.5 MiB");
}

TEST(ResidentBytes, GrowsWithTouchedMemoryAndStaysBelowThePeak) {
  const uint64_t before = residentBytes();
  ASSERT_GT(before, 0u) << "/proc/self/statm unreadable";
  constexpr size_t kBlock = 64u << 20;
  const auto block = std::make_unique<char[]>(kBlock);
  std::memset(block.get(), 1, kBlock);  // resident only once written
  const uint64_t after = residentBytes();
  EXPECT_GE(after, before + kBlock * 9 / 10);
  EXPECT_GE(peakResidentBytes(), after);
  volatile char sink = block[kBlock / 2];
  (void)sink;
}

}  // namespace
}  // namespace rmap::app
