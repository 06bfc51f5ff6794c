#pragma once
/// @file write_gate.h
/// The store's writer lock, fair to the checkpointer. With a plain mutex a
/// thread committing back to back takes it again before a waiting thread
/// wakes, so the checkpointer, which must hold the writers back for a moment
/// to let the WAL start over, could wait for as long as the stream of commits
/// lasts, and the WAL would grow with the log. Here a writer passes a
/// turnstile before it takes the lock: once the checkpointer waits in the
/// turnstile, the next commit waits behind it.

#include <mutex>

namespace rmap::store {

class WriteGate {
 public:
  /// Held by every write transaction.
  std::unique_lock<std::mutex> lockWriter() {
    std::lock_guard turn(turnstile_);
    return std::unique_lock(write_);
  }

  /// Runs `fn` once the current write transaction ended, with every writer held back.
  template <class Fn>
  void whileWritersWait(Fn&& fn) {
    std::lock_guard turn(turnstile_);
    std::lock_guard writers(write_);
    fn();
  }

 private:
  std::mutex turnstile_;
  std::mutex write_;
};

}  // namespace rmap::store
