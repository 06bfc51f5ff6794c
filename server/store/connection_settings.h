#pragma once
/// @file connection_settings.h
/// The pragmas every store connection runs with, private to the store.

#include "store/sqlite_connection.h"

namespace rmap::store {

/// How long a connection retries a database locked by another connection or
/// process (e.g. the sqlite3 shell, a checkpoint) before failing with SQLITE_BUSY.
inline constexpr int kBusyTimeoutMs = 10'000;

/// Busy timeout and page cache (`cache_bytes` per connection).
void applyCommonSettings(Connection& connection, int64_t cache_bytes);

/// Everything of applyCommonSettings plus, for the one writing connection:
/// page size (new databases only), WAL journal, synchronous=FULL (a commit
/// survives power loss), no automatic checkpoints and the size limit.
/// @throws StoreError e.g. when the file system cannot hold a WAL database
void applyWriterSettings(Connection& writer, const StoreOptions& options);

}  // namespace rmap::store
