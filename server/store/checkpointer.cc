#include "store/checkpointer.h"

#include <spdlog/spdlog.h>

#include "store/connection_settings.h"

namespace rmap::store {

Checkpointer::Checkpointer(const std::filesystem::path& database, int64_t cache_bytes, int restart_pages,
                           std::chrono::milliseconds period, WriteGate& write_gate)
    : connection_(database, SQLITE_OPEN_READWRITE),
      restart_pages_(restart_pages),
      period_(period),
      write_gate_(write_gate) {
  applyCommonSettings(connection_, cache_bytes);
  thread_ = std::thread([this] { run(); });
}

Checkpointer::~Checkpointer() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void Checkpointer::run() {
  std::unique_lock lock(mutex_);
  while (!wake_.wait_for(lock, period_, [this] { return stopping_; })) {
    lock.unlock();
    checkpoint();
    lock.lock();
  }
}

void Checkpointer::checkpoint() {
  int log_pages = 0;
  int copied_pages = 0;
  int rc = sqlite3_wal_checkpoint_v2(connection_.handle(), nullptr, SQLITE_CHECKPOINT_PASSIVE, &log_pages,
                                     &copied_pages);
  // A writer starts the WAL over only if every frame was copied before its
  // transaction began; back-to-back commits never leave that gap, so for a
  // long WAL the writers wait while the frames since the passive checkpoint
  // are copied (and SQLite's RESTART mode would starve behind them).
  if (rc == SQLITE_OK && log_pages >= restart_pages_ && log_pages != log_pages_at_restart_) {
    write_gate_.whileWritersWait([&] {
      rc = sqlite3_wal_checkpoint_v2(connection_.handle(), nullptr, SQLITE_CHECKPOINT_PASSIVE, &log_pages,
                                     &copied_pages);
    });
    log_pages_at_restart_ = log_pages;
  }
  // SQLITE_BUSY: readers or a writer held on past the busy timeout; the next round retries.
  if (rc != SQLITE_OK && rc != SQLITE_BUSY && !failing_) {
    spdlog::warn("store: checkpoint of {} failed: {} (logged once until checkpoints work again)",
                 connection_.file().string(), sqlite3_errmsg(connection_.handle()));
    failing_ = true;
  } else if (rc == SQLITE_OK && failing_) {
    spdlog::info("store: checkpoints of {} work again", connection_.file().string());
    failing_ = false;
  }
}

}  // namespace rmap::store
