#pragma once
/// @file reader_pool.h
/// Read-only connections for the store's queries, private to the store. With
/// WAL, readers see the last commit and neither wait for the writer nor make
/// it wait; a pool (instead of one reader under a mutex) lets a long replay
/// run while HTTP queries proceed, and lets a replay callback query the store.

#include <cstddef>
#include <filesystem>
#include <memory>
#include <mutex>
#include <vector>

#include "store/sqlite_connection.h"

namespace rmap::store {

class ReaderPool {
 public:
  /// Exclusive use of one reader until destroyed.
  class Lease {
   public:
    Lease(const ReaderPool& pool, std::unique_ptr<Connection> connection)
        : pool_(pool), connection_(std::move(connection)) {}
    ~Lease() { pool_.release(std::move(connection_)); }
    Lease(const Lease&) = delete;
    Lease& operator=(const Lease&) = delete;
    Connection& operator*() const { return *connection_; }

   private:
    const ReaderPool& pool_;
    std::unique_ptr<Connection> connection_;
  };

  /// @param cache_bytes page cache of each reader
  ReaderPool(std::filesystem::path file, int64_t cache_bytes);

  /// An idle reader, or a new one when all are busy (never waits).
  /// @throws StoreError when a new reader cannot be opened
  Lease acquire() const;

 private:
  /// Readers kept open when idle; more are opened under load and closed after.
  static constexpr size_t kMaxIdle = 4;

  std::unique_ptr<Connection> open() const;
  void release(std::unique_ptr<Connection> connection) const;

  std::filesystem::path file_;
  int64_t cache_bytes_;
  mutable std::mutex mutex_;
  mutable std::vector<std::unique_ptr<Connection>> idle_;
};

}  // namespace rmap::store
