#include "net/server_state.h"

namespace rmap::net {

ConnectionCount::ConnectionCount(std::atomic<size_t>& counter) : counter_(&counter) { ++*counter_; }

ConnectionCount::ConnectionCount(ConnectionCount&& other) noexcept : counter_(other.counter_) {
  other.counter_ = nullptr;
}

ConnectionCount::~ConnectionCount() {
  if (counter_ != nullptr) --*counter_;
}

ServerState::ServerState(const ServerOptions& options_in, Service& service_in)
    : options(options_in), service(service_in) {}

std::optional<ServerState::Handle> ServerState::enroll(std::weak_ptr<Session> session) {
  std::lock_guard lock(mutex_);
  if (stopping_) return std::nullopt;
  return sessions_.insert(sessions_.end(), std::move(session));
}

void ServerState::withdraw(Handle handle) {
  std::lock_guard lock(mutex_);
  sessions_.erase(handle);
}

std::vector<std::shared_ptr<Session>> ServerState::stopAll() {
  std::lock_guard lock(mutex_);
  stopping_ = true;
  std::vector<std::shared_ptr<Session>> alive;
  for (const auto& weak : sessions_) {
    if (auto session = weak.lock()) alive.push_back(std::move(session));
  }
  return alive;
}

}  // namespace rmap::net
