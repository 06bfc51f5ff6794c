#pragma once
/// @file parallel_for.h
/// Runs independent jobs on a few short-lived threads (block updates and
/// fusion of one scan); the caller's thread takes part.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <thread>
#include <vector>

namespace rmap::map3d {

/// Calls fn(i) for every i in [0, n), on up to `threads` threads, in chunks
/// handed out dynamically (blocks differ a lot in cost).
template <class Fn>
void parallelFor(size_t n, int threads, Fn&& fn) {
  constexpr size_t kChunk = 16;
  const size_t workers = std::min<size_t>(threads > 1 ? threads : 1, (n + kChunk - 1) / kChunk);
  if (workers <= 1) {
    for (size_t i = 0; i < n; ++i) fn(i);
    return;
  }
  std::atomic<size_t> next{0};
  auto work = [&] {
    for (size_t begin; (begin = next.fetch_add(kChunk)) < n;) {
      for (size_t i = begin, end = std::min(n, begin + kChunk); i < end; ++i) fn(i);
    }
  };
  std::vector<std::thread> pool;
  for (size_t t = 1; t < workers; ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
}

}  // namespace rmap::map3d
