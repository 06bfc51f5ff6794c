#pragma once
/// @file server.h
/// One listening port for HTTP/1.1 (keep-alive) and WebSocket, on a pool of
/// I/O threads (Boost.Beast on Asio). Requests are parsed with bounded header
/// and body sizes; malformed or oversize requests (ambiguous body framing and
/// WebSocket handshakes that cannot succeed included) get a JSON error
/// response (see json_error.h) without reaching the Service. With a TLS
/// context every connection is TLS (https://, wss://): a client that does not
/// complete the TLS handshake within the idle timeout, plain HTTP included,
/// is disconnected without an answer.

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "net/service.h"

namespace boost::asio::ssl {
class context;
}

namespace rmap::net {

struct ServerOptions {
  std::string host = "127.0.0.1";
  uint16_t port = 8080;  ///< 0 picks a free port (see Server::port)
  int io_threads = 2;
  size_t max_header_bytes = 16u << 10;
  size_t max_body_bytes = 64u << 20;  ///< larger bodies → 413
  /// A connection idle (no complete request / no frame) this long is closed.
  /// HTTP: each request (header and body) and each response write must
  /// complete within it. WebSocket: the server pings after half of it, and
  /// closes when nothing (not even the pong) arrived for all of it; while
  /// the application paused reading, bytes waiting unread count as arrived.
  std::chrono::seconds idle_timeout{120};
  /// Further connections are accepted and closed at once.
  size_t max_connections = 4096;
  /// stop() gives each open WebSocket this long to answer its close frame
  /// (1001, going away) before its socket is closed.
  std::chrono::milliseconds close_timeout{1000};
  /// Null: plain TCP. Otherwise the port speaks only TLS with this context
  /// (see tls_context.h); shared by every connection, not modified after start().
  std::shared_ptr<boost::asio::ssl::context> tls;
};

class Server {
 public:
  Server(const ServerOptions& options, Service& service);
  ~Server();  ///< stops
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  /// Binds, listens and starts the I/O threads (at least one).
  /// @throws std::runtime_error naming the address when binding fails
  /// @throws std::logic_error when called after a successful start or a stop
  ///         (a Server runs once)
  void start();
  /// Closes the listener and every connection, joins the threads. Idempotent.
  /// Not from an I/O thread (it joins them). HTTP connections close at once;
  /// open WebSockets get a close frame (1001, going away) in place of their
  /// queued frames, and are closed when the peer answered it or after
  /// close_timeout. WebSocket handlers get onClose; WsConnections they still
  /// hold refuse sends from then on.
  void stop();
  /// The bound port (after start).
  uint16_t port() const;
  /// Open connections (HTTP and WebSocket).
  size_t connections() const;
  /// Open WebSocket connections.
  size_t webSocketConnections() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rmap::net
