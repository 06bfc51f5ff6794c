#pragma once
/// @file checkpointer.h
/// Copies WAL frames into the database file on a thread and connection of its
/// own, private to the store. Done inside a commit (SQLite's automatic
/// checkpoint), the copy of tens of MB plus an fsync of the database file
/// stalls every message waiting on that commit for hundreds of ms.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <thread>

#include "store/sqlite_connection.h"
#include "store/write_gate.h"

namespace rmap::store {

class Checkpointer {
 public:
  /// @param restart_pages  WAL length in pages from which a checkpoint holds
  ///   the writers back while it copies the few frames passive checkpoints left,
  ///   so that the next write starts the WAL over and it cannot grow without
  ///   bound under a steady stream of commits
  /// @param period  time between passive checkpoints
  /// @param write_gate  the store's writer lock, held by every write transaction
  /// @throws StoreError when the database cannot be opened
  Checkpointer(const std::filesystem::path& database, int64_t cache_bytes, int restart_pages,
               std::chrono::milliseconds period, WriteGate& write_gate);
  /// Stops the thread; a checkpoint in progress completes first.
  ~Checkpointer();
  Checkpointer(const Checkpointer&) = delete;
  Checkpointer& operator=(const Checkpointer&) = delete;

 private:
  void run();
  /// One passive checkpoint, then a restarting one when the WAL is long.
  void checkpoint();

  Connection connection_;
  int restart_pages_;
  int log_pages_at_restart_ = -1;  ///< WAL length seen by the last restarting checkpoint
  /// The last checkpoint failed: a full disk fails every one, 10 per second, so
  /// only the first failure and the recovery are logged.
  bool failing_ = false;
  std::chrono::milliseconds period_;
  WriteGate& write_gate_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace rmap::store
