#include "store/connection_settings.h"

#include <algorithm>
#include <string>

namespace rmap::store {
namespace {

/// Page size of new databases. Payloads of ~100 KB live in chains of overflow
/// pages; bigger pages mean fewer page and WAL frame headers per payload.
/// Measured on the target VM: 16 KiB appends 100 KB payloads ~10 % faster
/// than 4 KiB and 32 KiB; 64 KiB wastes 30 % of the file on partly filled pages.
constexpr int kPageSizeBytes = 16384;

/// The WAL file is truncated back to this size after a checkpoint, so one huge
/// transaction, or a long replay holding back checkpoints, does not leave it
/// large for good.
constexpr int64_t kWalSizeLimitBytes = 64ll << 20;

int64_t queryInt64(Connection& connection, std::string_view pragma) {
  Statement query(connection, pragma, pragma);
  if (!query.step()) throw StoreError(std::string(pragma) + " returned nothing on " + connection.file().string());
  return query.int64At(0);
}

}  // namespace

void applyCommonSettings(Connection& connection, int64_t cache_bytes) {
  sqlite3_busy_timeout(connection.handle(), kBusyTimeoutMs);
  // Opening reads nothing yet: this first read reports a file that is not a database.
  connection.exec("PRAGMA schema_version", "read database");
  // A negative cache_size counts KiB instead of pages.
  connection.exec("PRAGMA cache_size = " + std::to_string(-std::max<int64_t>(cache_bytes / 1024, 1)),
                  "set page cache size");
}

void applyWriterSettings(Connection& writer, const StoreOptions& options) {
  applyCommonSettings(writer, options.cache_bytes);
  writer.exec("PRAGMA page_size = " + std::to_string(kPageSizeBytes), "set page size");  // no-op once written
  {
    Statement journal(writer, "PRAGMA journal_mode = WAL", "enable WAL journal");
    if (!journal.step() || journal.textAt(0) != "wal")
      throw StoreError("cannot use a WAL journal for " + writer.file().string() +
                       " (the file system must support shared memory, e.g. not a network share)");
  }
  writer.exec("PRAGMA synchronous = FULL", "set synchronous=FULL");
  // Checkpoints run on the store's Checkpointer, never inside a commit.
  writer.exec("PRAGMA wal_autocheckpoint = 0", "disable checkpoints in commits");
  writer.exec("PRAGMA journal_size_limit = " + std::to_string(kWalSizeLimitBytes), "set WAL size limit");
  if (options.max_database_bytes > 0) {
    const int64_t page_bytes = queryInt64(writer, "PRAGMA page_size");
    writer.exec("PRAGMA max_page_count = " + std::to_string(std::max<int64_t>(options.max_database_bytes / page_bytes, 1)),
                "set database size limit");
  }
}

}  // namespace rmap::store
