#include "slam2d/closure_ledger.h"

namespace rmap::slam2d {

void ClosureLedger::await(size_t edge, const KeyframeClosure& closure) { awaiting_.emplace_back(edge, closure); }

ClosureLedger::Settled ClosureLedger::settle(const std::function<bool(size_t)>& enabled) {
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
  for (const auto& [edge, closure] : awaiting_) {
    if (!enabled(edge)) continue;
    accepted_.push_back(closure);
    held_.emplace(edge, closure);
    ++settled.accepted;
  }
  awaiting_.clear();
  return settled;
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
