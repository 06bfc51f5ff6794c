#include "store/group_commit.h"

#include <algorithm>
#include <vector>

namespace rmap::store {

GroupCommitter::GroupCommitter(Store& store, const GroupCommitOptions& options)
    : store_(store), options_(options), writer_([this] { run(); }) {}

GroupCommitter::~GroupCommitter() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_one();
  writer_.join();
}

bool GroupCommitter::submit(MessageRecord message, Completion done) {
  const size_t bytes = message.payload.size();
  {
    std::lock_guard lock(mutex_);
    // With nothing pending any message is taken, so one larger than the bound still gets through.
    if (stopping_ || (queued_bytes_ > 0 && queued_bytes_ + bytes > options_.max_queued_bytes)) return false;
    queue_.push_back({std::move(message), std::move(done)});
    queued_bytes_ += bytes;
  }
  wake_.notify_one();
  return true;
}

size_t GroupCommitter::queuedMessages() const {
  std::lock_guard lock(mutex_);
  return queue_.size();
}

size_t GroupCommitter::queuedBytes() const {
  std::lock_guard lock(mutex_);
  return queued_bytes_;
}

uint64_t GroupCommitter::committedBatches() const {
  std::lock_guard lock(mutex_);
  return batches_;
}

void GroupCommitter::run() {
  std::vector<MessageRecord> batch;  // contiguous, as Store::append takes a span
  std::vector<Completion> completions;
  for (;;) {
    size_t batch_bytes = 0;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
      if (queue_.empty()) return;  // stopping, and everything submitted is committed
      // Everything queued while the previous batch was being committed forms
      // the next one: the busier the store, the larger the batches.
      while (!queue_.empty() && batch.size() < std::max<size_t>(options_.max_batch_messages, 1)) {
        const size_t bytes = queue_.front().message.payload.size();
        if (!batch.empty() && batch_bytes + bytes > options_.max_batch_bytes) break;
        batch_bytes += bytes;
        batch.push_back(std::move(queue_.front().message));
        completions.push_back(std::move(queue_.front().done));
        queue_.pop_front();
      }
    }

    std::vector<AppendResult> results;
    std::exception_ptr error;
    try {
      results = store_.append(batch);
    } catch (...) {
      error = std::current_exception();
    }
    {
      // Released before the completions run, so a session resubmitting from
      // its completion is not refused for bytes already committed.
      std::lock_guard lock(mutex_);
      queued_bytes_ -= batch_bytes;
      if (!error) ++batches_;
    }
    for (size_t i = 0; i < completions.size(); ++i) completions[i](error ? AppendResult{} : results[i], error);
    batch.clear();
    completions.clear();
  }
}

}  // namespace rmap::store
