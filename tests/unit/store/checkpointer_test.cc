#include <gtest/gtest.h>

#include <filesystem>

#include "store/store.h"
#include "temp_dir.h"

namespace rmap::store {
namespace {

uint64_t walBytes(const std::filesystem::path& data_dir) {
  std::error_code error;
  const auto size = std::filesystem::file_size(data_dir / "rmap.db-wal", error);
  return error ? 0 : size;
}

// A steady stream of commits, as from the group committer: the background
// checkpoints keep the WAL short although no commit checkpoints by itself.
TEST(Checkpointer, WalStaysBoundedUnderSteadyCommits) {
  TempDir dir;
  StoreOptions options;
  options.wal_checkpoint_period_ms = 5;
  options.wal_restart_pages = 64;  // 1 MiB of 16 KiB pages
  auto store = Store::open(dir.path(), options);
  const std::string payload(100'000, 'x');
  uint64_t largest_wal = 0;
  for (uint64_t seq = 1; seq <= 400; ++seq) {  // 40 MB in 400 commits
    store->append(std::vector<MessageRecord>{{"m", "r", seq, 1, 0, payload}});
    largest_wal = std::max(largest_wal, walBytes(dir.path()));
  }
  EXPECT_LT(largest_wal, 12u << 20) << "the WAL grew with the log instead of restarting";
  EXPECT_EQ(store->messageCount(), 400u);
  uint64_t replayed = 0;
  store->forEachMessage("m", 0, [&](const StoredMessage& m) {
    EXPECT_EQ(m.record.payload.size(), payload.size());
    ++replayed;
    return true;
  });
  EXPECT_EQ(replayed, 400u);
}

TEST(Checkpointer, BadOptionsAreRefused) {
  TempDir dir;
  StoreOptions options;
  options.wal_checkpoint_period_ms = 0;
  EXPECT_THROW(Store::open(dir.path(), options), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::store
