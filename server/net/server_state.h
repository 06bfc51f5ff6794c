#pragma once
/// @file server_state.h
/// Private to the net layer: what every session of one Server shares (options,
/// the Service, the counters) and the registry through which stop() reaches
/// the live sessions. Sessions hold it by shared_ptr, so it outlives them.

#include <atomic>
#include <cstddef>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "net/server.h"

namespace rmap::net {

/// A live connection as stop() sees it.
class Session {
 public:
  virtual ~Session() = default;
  /// Ends the connection; callable from any thread, the work runs on the
  /// session's strand.
  virtual void shutdown() = 0;
};

/// Holds one unit of a connection counter for as long as it lives; moves with
/// the connection from the HTTP session to the WebSocket session after an
/// upgrade so the connection is never counted twice.
class ConnectionCount {
 public:
  explicit ConnectionCount(std::atomic<size_t>& counter);
  ConnectionCount(ConnectionCount&& other) noexcept;
  ConnectionCount& operator=(ConnectionCount&&) = delete;
  ~ConnectionCount();

 private:
  std::atomic<size_t>* counter_;
};

class ServerState {
 public:
  using Handle = std::list<std::weak_ptr<Session>>::iterator;

  ServerState(const ServerOptions& options, Service& service);

  const ServerOptions options;
  Service& service;
  std::atomic<size_t> connections{0};
  std::atomic<size_t> web_sockets{0};

  /// Registers a live session; nullopt once the server is stopping, in which
  /// case the caller closes its connection at once.
  std::optional<Handle> enroll(std::weak_ptr<Session> session);
  /// Unregisters (from the session's destructor).
  void withdraw(Handle handle);
  /// Marks the server as stopping (later enroll() calls fail) and returns the
  /// sessions still alive.
  std::vector<std::shared_ptr<Session>> stopAll();

 private:
  std::mutex mutex_;
  bool stopping_ = false;
  std::list<std::weak_ptr<Session>> sessions_;
};

}  // namespace rmap::net
