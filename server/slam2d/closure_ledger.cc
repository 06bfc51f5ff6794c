#include "slam2d/closure_ledger.h"

#include <stdexcept>

namespace rmap::slam2d {

ClosureLedger::ClosureLedger(int64_t hold_ns) : hold_ns_(hold_ns) {
  if (hold_ns < 0) throw std::invalid_argument("ClosureLedger: hold_ns must be >= 0");
}

void ClosureLedger::await(size_t edge, const KeyframeClosure& closure, size_t trajectory) {
  awaiting_.push_back({edge, closure, trajectory, 0});
}

void ClosureLedger::accept(const Entry& entry) {
  accepted_.push_back(entry.closure);
  // Held for as long as the graph lives: without its submap (a kilobyte per closure).
  KeyframeClosure held = entry.closure;
  held.submap = {};
  held_.emplace(entry.edge, std::move(held));
}

ClosureLedger::Settled ClosureLedger::settle(const std::function<bool(size_t)>& enabled,
                                             const std::function<int64_t(size_t)>& now_ns) {
  Settled settled;
  // Withdrawn first: a closure accepted below has just come through this optimisation.
  for (auto it = held_.begin(); it != held_.end();) {
    if (enabled(it->first)) {
      ++it;
      continue;
    }
    withdrawn_.push_back(it->second);
    ++settled.withdrawn;
    it = held_.erase(it);
  }
  for (const Entry& entry : tentative_) {
    if (enabled(entry.edge)) {
      accept(entry);
      ++settled.accepted;
    } else {
      ++settled.dropped_tentative;
    }
  }
  tentative_.clear();
  for (Entry& entry : awaiting_) {
    if (!enabled(entry.edge)) continue;
    if (hold_ns_ == 0) {
      accept(entry);
      ++settled.accepted;
    } else {
      entry.kept_ns = now_ns(entry.trajectory);
      tentative_.push_back(entry);
    }
  }
  awaiting_.clear();
  return settled;
}

size_t ClosureLedger::confirmHeld(size_t trajectory, int64_t now_ns) {
  if (tentative_.empty()) return 0;  // the common case: called for every scan
  size_t accepted = 0;
  std::vector<Entry> still;
  for (const Entry& entry : tentative_) {
    if (entry.trajectory == trajectory && now_ns - entry.kept_ns >= hold_ns_) {
      accept(entry);
      ++accepted;
    } else {
      still.push_back(entry);
    }
  }
  tentative_ = std::move(still);
  return accepted;
}

size_t ClosureLedger::confirmAll() {
  for (const Entry& entry : tentative_) accept(entry);
  const size_t accepted = tentative_.size();
  tentative_.clear();
  return accepted;
}

std::vector<KeyframeClosure> ClosureLedger::takeAccepted() {
  std::vector<KeyframeClosure> out;
  out.swap(accepted_);
  return out;
}

std::vector<KeyframeClosure> ClosureLedger::takeWithdrawn() {
  std::vector<KeyframeClosure> out;
  out.swap(withdrawn_);
  return out;
}

}  // namespace rmap::slam2d
