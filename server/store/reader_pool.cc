#include "store/reader_pool.h"

#include "store/connection_settings.h"

namespace rmap::store {

ReaderPool::ReaderPool(std::filesystem::path file, int64_t cache_bytes)
    : file_(std::move(file)), cache_bytes_(cache_bytes) {}

ReaderPool::Lease ReaderPool::acquire() const {
  {
    std::lock_guard lock(mutex_);
    if (!idle_.empty()) {
      std::unique_ptr<Connection> connection = std::move(idle_.back());
      idle_.pop_back();
      return Lease(*this, std::move(connection));
    }
  }
  return Lease(*this, open());  // opened outside the lock: other readers need not wait for it
}

std::unique_ptr<Connection> ReaderPool::open() const {
  auto connection = std::make_unique<Connection>(file_, SQLITE_OPEN_READONLY);
  applyCommonSettings(*connection, cache_bytes_);
  return connection;
}

void ReaderPool::release(std::unique_ptr<Connection> connection) const {
  std::lock_guard lock(mutex_);
  if (idle_.size() < kMaxIdle) idle_.push_back(std::move(connection));
}  // a surplus reader, still in `connection`, closes after the lock is released

}  // namespace rmap::store
