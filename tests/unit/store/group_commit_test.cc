#include "store/group_commit.h"

#include <gtest/gtest.h>

#include <map>
#include <set>
#include <thread>

#include "temp_dir.h"

namespace rmap::store {
namespace {

MessageRecord message(const std::string& robot, uint64_t seq, size_t payload_bytes) {
  std::string payload(payload_bytes, static_cast<char>('a' + seq % 26));
  const std::string tag = robot + "#" + std::to_string(seq);  // makes every payload distinct
  if (payload_bytes >= tag.size()) payload.replace(0, tag.size(), tag);
  return {"hall", robot, seq, 1, static_cast<int64_t>(seq), std::move(payload)};
}

/// A store whose append() blocks until the test opens the gate, records the
/// batches it gets and, when told to, fails like a full disk.
class GatedStore final : public Store {
 public:
  std::vector<AppendResult> append(std::span<const MessageRecord> messages) override {
    std::unique_lock lock(mutex_);
    ++appends_started_;
    changed_.notify_all();
    changed_.wait(lock, [this] { return open_; });
    batch_sizes_.push_back(messages.size());
    if (fail_) throw StoreError("append messages failed: database or disk is full");
    std::vector<AppendResult> results;
    for (size_t i = 0; i < messages.size(); ++i) results.push_back({++last_id_, false});
    return results;
  }

  void openGate(bool fail = false) {
    std::lock_guard lock(mutex_);
    open_ = true;
    fail_ = fail;
    changed_.notify_all();
  }
  void waitForAppendsStarted(int count) {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return appends_started_ >= count; });
  }
  std::vector<size_t> batchSizes() const {
    std::lock_guard lock(mutex_);
    return batch_sizes_;
  }

  // Not used by the committer.
  void forEachMessage(const std::string&, int64_t, const std::function<bool(const StoredMessage&)>&) const override {}
  uint64_t messageCount() const override { return 0; }
  uint64_t lastSeq(const std::string&) const override { return 0; }
  MapRecord ensureMap(const MapRecord& map) override { return map; }
  std::vector<MapRecord> maps() const override { return {}; }
  void upsertRobot(const RobotRecord&) override {}
  std::vector<RobotRecord> robots() const override { return {}; }
  std::optional<RobotRecord> robot(const std::string&) const override { return std::nullopt; }
  void appendTrajectory(const std::string&, std::span<const TrajectoryPose>) override {}
  std::vector<TrajectoryPose> trajectory(const std::string&, int64_t, size_t) const override { return {}; }
  int64_t appendEvent(const EventRecord&) override { return 0; }
  std::vector<EventRecord> events(const std::string&, int64_t, size_t) const override { return {}; }
  std::optional<int64_t> appendLoopClosure(const LoopClosureRecord&) override { return std::nullopt; }
  std::optional<LoopClosureRecord> withdrawLoopClosure(const LoopClosureRecord&, int64_t) override {
    return std::nullopt;
  }
  std::vector<LoopClosureRecord> loopClosures(const LoopClosureFilter&) const override { return {}; }
  void putSnapshot(const Snapshot&) override {}
  std::optional<Snapshot> snapshot(const std::string&) const override { return std::nullopt; }

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  bool open_ = false;
  bool fail_ = false;
  int appends_started_ = 0;
  int64_t last_id_ = 0;
  std::vector<size_t> batch_sizes_;
};

/// Completions as they arrive (on the committer's thread).
class Completions {
 public:
  GroupCommitter::Completion record(std::string robot, uint64_t seq) {
    return [this, robot = std::move(robot), seq](const AppendResult& result, std::exception_ptr error) {
      std::lock_guard lock(mutex_);
      done_.push_back({robot, seq, result, error});
      changed_.notify_all();
    };
  }
  void waitFor(size_t count) {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return done_.size() >= count; });
  }

  struct Done {
    std::string robot;
    uint64_t seq;
    AppendResult result;
    std::exception_ptr error;
  };
  std::vector<Done> done() const {
    std::lock_guard lock(mutex_);
    return done_;
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<Done> done_;
};

TEST(GroupCommitter, ConcurrentSubmittersAreCompletedOnceEachInLogOrder) {
  TempDir tmp;
  const auto store = Store::open(tmp.path());
  constexpr int kRobots = 8;
  constexpr uint64_t kMessagesPerRobot = 250;
  Completions completions;
  uint64_t batches = 0;
  {
    GroupCommitter committer(*store);
    std::vector<std::thread> robots;
    for (int r = 0; r < kRobots; ++r)
      robots.emplace_back([&, robot = "robot" + std::to_string(r)] {
        for (uint64_t seq = 1; seq <= kMessagesPerRobot; ++seq)
          ASSERT_TRUE(committer.submit(message(robot, seq, 1000), completions.record(robot, seq)));
      });
    for (std::thread& t : robots) t.join();
    completions.waitFor(kRobots * kMessagesPerRobot);
    batches = committer.committedBatches();
  }
  const auto done = completions.done();
  ASSERT_EQ(done.size(), kRobots * kMessagesPerRobot);  // none called twice, even after the drain
  std::set<std::pair<std::string, uint64_t>> distinct;
  int64_t previous_id = 0;
  for (const auto& d : done) {
    EXPECT_FALSE(d.error);
    EXPECT_FALSE(d.result.duplicate);
    EXPECT_GT(d.result.id, previous_id);
    previous_id = d.result.id;
    distinct.insert({d.robot, d.seq});
  }
  EXPECT_EQ(distinct.size(), done.size());
  EXPECT_GT(batches, 0u);
  EXPECT_LT(batches, done.size()) << "no message shared a transaction";

  std::map<int64_t, MessageRecord> stored;
  store->forEachMessage("", 0, [&](const StoredMessage& m) {
    stored[m.id] = m.record;
    return true;
  });
  ASSERT_EQ(stored.size(), done.size());
  for (const auto& d : done) {
    const MessageRecord& record = stored.at(d.result.id);
    EXPECT_EQ(record.robot_id, d.robot);
    EXPECT_EQ(record.seq, d.seq);
    EXPECT_EQ(record.payload, message(d.robot, d.seq, 1000).payload);
  }
}

TEST(GroupCommitter, BatchesTakeWhatIsQueuedUpToTheMessageLimit) {
  GatedStore store;
  GroupCommitOptions options;
  options.max_batch_messages = 4;
  Completions completions;
  {
    GroupCommitter committer(store, options);
    ASSERT_TRUE(committer.submit(message("r", 1, 10), completions.record("r", 1)));
    store.waitForAppendsStarted(1);  // the first batch holds message 1 alone
    for (uint64_t seq = 2; seq <= 11; ++seq) ASSERT_TRUE(committer.submit(message("r", seq, 10), completions.record("r", seq)));
    EXPECT_EQ(committer.queuedMessages(), 10u);
    store.openGate();
  }
  EXPECT_EQ(store.batchSizes(), (std::vector<size_t>{1, 4, 4, 2}));
  const auto done = completions.done();
  ASSERT_EQ(done.size(), 11u);
  for (size_t i = 0; i < done.size(); ++i) {
    EXPECT_EQ(done[i].seq, i + 1);
    EXPECT_EQ(done[i].result.id, static_cast<int64_t>(i + 1));
  }
}

TEST(GroupCommitter, BatchesStayWithinTheByteLimitButTakeAnOversizedMessageAlone) {
  GatedStore store;
  GroupCommitOptions options;
  options.max_batch_bytes = 250;
  Completions completions;
  {
    GroupCommitter committer(store, options);
    ASSERT_TRUE(committer.submit(message("r", 1, 100), completions.record("r", 1)));
    store.waitForAppendsStarted(1);
    for (uint64_t seq = 2; seq <= 6; ++seq) ASSERT_TRUE(committer.submit(message("r", seq, 100), completions.record("r", seq)));
    ASSERT_TRUE(committer.submit(message("r", 7, 1000), completions.record("r", 7)));
    ASSERT_TRUE(committer.submit(message("r", 8, 100), completions.record("r", 8)));
    store.openGate();
  }
  EXPECT_EQ(store.batchSizes(), (std::vector<size_t>{1, 2, 2, 1, 1, 1}));
  EXPECT_EQ(completions.done().size(), 8u);
}

TEST(GroupCommitter, FailedAppendReachesEveryCompletionOfTheBatch) {
  GatedStore store;
  Completions completions;
  uint64_t batches = 0;
  {
    GroupCommitter committer(store);
    for (uint64_t seq = 1; seq <= 5; ++seq) ASSERT_TRUE(committer.submit(message("r", seq, 10), completions.record("r", seq)));
    store.openGate(/*fail=*/true);
    completions.waitFor(5);
    batches = committer.committedBatches();
  }
  EXPECT_EQ(batches, 0u);
  const auto done = completions.done();
  ASSERT_EQ(done.size(), 5u);
  for (const auto& d : done) {
    ASSERT_TRUE(d.error);
    EXPECT_THROW(std::rethrow_exception(d.error), StoreError);
  }
}

TEST(GroupCommitter, RefusesSubmissionsOverTheQueuedByteBoundUntilCommitted) {
  GatedStore store;
  GroupCommitOptions options;
  options.max_queued_bytes = 1000;
  Completions completions;
  GroupCommitter committer(store, options);
  uint64_t accepted = 0;
  while (committer.submit(message("r", accepted + 1, 100), completions.record("r", accepted + 1))) {
    ++accepted;
    ASSERT_LE(accepted, 10u);
  }
  EXPECT_EQ(accepted, 10u);  // the batch being committed still counts
  EXPECT_EQ(committer.queuedBytes(), 1000u);

  store.openGate();
  completions.waitFor(accepted);
  EXPECT_EQ(completions.done().size(), accepted);  // the refused one is never completed
  EXPECT_EQ(committer.queuedBytes(), 0u);
  EXPECT_EQ(committer.queuedMessages(), 0u);
  // Committed bytes are released; a message larger than the bound passes alone.
  EXPECT_TRUE(committer.submit(message("r", 100, 5000), completions.record("r", 100)));
  completions.waitFor(accepted + 1);
}

TEST(GroupCommitter, DestructorCommitsEverythingQueued) {
  TempDir tmp;
  const auto store = Store::open(tmp.path());
  Completions completions;
  constexpr uint64_t kMessages = 300;
  {
    GroupCommitter committer(*store);
    for (uint64_t seq = 1; seq <= kMessages; ++seq) ASSERT_TRUE(committer.submit(message("r", seq, 200), completions.record("r", seq)));
  }
  const auto done = completions.done();
  ASSERT_EQ(done.size(), kMessages);
  for (const auto& d : done) EXPECT_FALSE(d.error);
  EXPECT_EQ(store->messageCount(), kMessages);
  EXPECT_EQ(store->lastSeq("r"), kMessages);
}

}  // namespace
}  // namespace rmap::store
