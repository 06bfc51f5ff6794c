#pragma once
/// @file group_commit.h
/// Batches robot messages from many sessions into few transactions so that
/// durability (one fsync per commit) does not cap throughput: one writer
/// thread takes everything queued, appends it in one transaction and then
/// calls each message's completion in log order.

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>

#include "store/store.h"

namespace rmap::store {

struct GroupCommitOptions {
  /// Most messages per transaction.
  size_t max_batch_messages = 512;
  /// Most payload bytes per transaction.
  size_t max_batch_bytes = 32u << 20;
  /// Payload bytes queued but not yet committed beyond which submit() refuses.
  size_t max_queued_bytes = 256u << 20;
};

class GroupCommitter {
 public:
  /// Called on the writer thread after the batch holding the message
  /// committed (error == nullptr) or failed (error set, nothing written).
  /// It must not throw, and should be quick: the next batch waits for it.
  using Completion = std::function<void(const AppendResult& result, std::exception_ptr error)>;

  GroupCommitter(Store& store, const GroupCommitOptions& options = {});
  /// Commits what is queued, then stops the writer thread.
  ~GroupCommitter();
  GroupCommitter(const GroupCommitter&) = delete;
  GroupCommitter& operator=(const GroupCommitter&) = delete;

  /// Queues a message; `done` runs once it is durable (or failed).
  /// @return false (and `done` is not called) when the queue is over
  ///         max_queued_bytes or the committer is stopping
  bool submit(MessageRecord message, Completion done);

  size_t queuedMessages() const;
  size_t queuedBytes() const;
  uint64_t committedBatches() const;

 private:
  struct Pending {
    MessageRecord message;
    Completion done;
  };
  void run();

  Store& store_;
  GroupCommitOptions options_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Pending> queue_;
  size_t queued_bytes_ = 0;
  uint64_t batches_ = 0;
  bool stopping_ = false;
  std::thread writer_;
};

}  // namespace rmap::store
