// A writer killed with SIGKILL loses nothing it acknowledged, and the database
// it leaves behind opens and passes SQLite's integrity check.

#include <signal.h>
#include <sqlite3.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cstring>
#include <map>

#include "store/store.h"
#include "temp_dir.h"

namespace rmap::store {
namespace {

constexpr char kRobot[] = "crash_robot";

/// Sizes from 2 KB to 32 KB, contents that tell every seq apart.
std::string payloadOf(uint64_t seq) {
  std::string payload(2000 + (seq * 7919) % 30000, '\0');
  for (size_t i = 0; i < payload.size(); ++i) payload[i] = static_cast<char>((seq * 31 + i * 7) % 251);
  return payload;
}

/// What the child reports after append() returned: the message is durable.
struct Ack {
  int64_t id;
  uint64_t seq;
};

/// The child: appends batches of 8 messages forever, acknowledging each batch
/// with one write (atomic: below PIPE_BUF). Ends only when killed.
[[noreturn]] void appendUntilKilled(const std::filesystem::path& data_dir, int ack_pipe) {
  prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlives a parent that died
  try {
    const auto store = Store::open(data_dir);
    for (uint64_t seq = 1;; seq += 8) {
      std::vector<MessageRecord> batch;
      for (uint64_t s = seq; s < seq + 8; ++s) batch.push_back({"hall", kRobot, s, 1, 0, payloadOf(s)});
      const auto results = store->append(batch);
      Ack acks[8];
      for (size_t i = 0; i < 8; ++i) acks[i] = {results[i].id, batch[i].seq};
      if (write(ack_pipe, acks, sizeof(acks)) != static_cast<ssize_t>(sizeof(acks))) _exit(2);
    }
  } catch (...) {
    _exit(1);
  }
}

/// Reads acks until `wanted` arrived (or, with wanted == 0, until end of file).
void readAcks(int ack_pipe, std::vector<Ack>& acks, std::string& partial, size_t wanted) {
  char buffer[4096];
  while (wanted == 0 || acks.size() < wanted) {
    const ssize_t got = read(ack_pipe, buffer, sizeof(buffer));
    if (got <= 0) return;
    partial.append(buffer, static_cast<size_t>(got));
    size_t used = 0;
    for (; partial.size() - used >= sizeof(Ack); used += sizeof(Ack)) {
      Ack ack;
      std::memcpy(&ack, partial.data() + used, sizeof(Ack));
      acks.push_back(ack);
    }
    partial.erase(0, used);
  }
}

std::string integrityCheck(const std::filesystem::path& database) {
  sqlite3* db = nullptr;
  std::string result = "cannot open";
  if (sqlite3_open(database.c_str(), &db) == SQLITE_OK) {
    sqlite3_stmt* check = nullptr;
    if (sqlite3_prepare_v2(db, "PRAGMA integrity_check", -1, &check, nullptr) == SQLITE_OK &&
        sqlite3_step(check) == SQLITE_ROW)
      result = reinterpret_cast<const char*>(sqlite3_column_text(check, 0));
    sqlite3_finalize(check);
  }
  sqlite3_close(db);
  return result;
}

TEST(StoreCrash, EveryAcknowledgedMessageSurvivesKill9) {
  TempDir tmp;
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0) << std::strerror(errno);
  if (child == 0) {
    close(fds[0]);
    appendUntilKilled(tmp.path(), fds[1]);
  }
  close(fds[1]);

  std::vector<Ack> acks;
  std::string partial;
  // One read may bring more acks than wanted (the writer runs on meanwhile): at least 400.
  readAcks(fds[0], acks, partial, 400);
  ASSERT_GE(acks.size(), 400u) << "the writer stopped early";
  kill(child, SIGKILL);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
  readAcks(fds[0], acks, partial, 0);  // acknowledged before the kill but not yet read
  close(fds[0]);
  EXPECT_TRUE(partial.empty());

  ASSERT_TRUE(std::filesystem::exists(tmp.path() / "rmap.db-wal")) << "the kill left no WAL to recover";
  const auto store = Store::open(tmp.path());
  std::map<int64_t, StoredMessage> stored;
  store->forEachMessage("hall", 0, [&](const StoredMessage& m) {
    stored[m.id] = m;
    return true;
  });
  for (const Ack& ack : acks) {
    const auto found = stored.find(ack.id);
    ASSERT_NE(found, stored.end()) << "acknowledged message " << ack.seq << " lost";
    EXPECT_EQ(found->second.record.seq, ack.seq);
    EXPECT_EQ(found->second.record.payload, payloadOf(ack.seq)) << "seq " << ack.seq;
  }
  // Batches commit whole and in order: the log holds seq 1..n without a gap.
  EXPECT_EQ(stored.size() % 8, 0u);
  EXPECT_EQ(store->lastSeq(kRobot), stored.size());
  EXPECT_GE(store->messageCount(), acks.size());
  EXPECT_FALSE(store->append(std::vector{MessageRecord{"hall", kRobot, stored.size() + 1, 1, 0, "after"}})[0].duplicate);
  EXPECT_EQ(integrityCheck(tmp.path() / "rmap.db"), "ok");
}

}  // namespace
}  // namespace rmap::store
