#pragma once
/// @file service.h
/// What the network layer asks of the application: answer HTTP requests and
/// decide on WebSocket upgrades. The net layer owns sockets, parsing, limits
/// and timeouts; the application owns routes, auth and meaning.

#include <boost/beast/http/message.hpp>
#include <boost/beast/http/string_body.hpp>
#include <cstdint>
#include <memory>
#include <string>

namespace rmap::net {

using Request = boost::beast::http::request<boost::beast::http::string_body>;
using Response = boost::beast::http::response<boost::beast::http::string_body>;

/// The remote end of a connection.
struct Peer {
  std::string address;  ///< textual IP address
  uint16_t port = 0;
  bool loopback = false;  ///< 127.0.0.0/8 or ::1
};

/// A WebSocket connection as handlers see it. Every method is thread-safe and
/// never blocks on the network.
class WsConnection {
 public:
  virtual ~WsConnection() = default;
  /// Queues a frame for sending.
  /// @return false when the frame would take the send queue over its byte
  ///         bound (the frame is dropped, the connection stays open) or the
  ///         connection is closed
  virtual bool send(std::string data, bool binary) = 0;
  /// Bytes queued and not yet written to the socket.
  virtual size_t queuedBytes() const = 0;
  /// Stops (true) or resumes (false) reading frames: back-pressure towards a
  /// client that sends faster than its messages are handled.
  virtual void pauseReading(bool paused) = 0;
  /// Sends a close frame after the queued frames and ends the connection.
  virtual void close(uint16_t code, const std::string& reason) = 0;
  virtual const Peer& peer() const = 0;
};

/// Receives the events of one WebSocket connection. Calls for one connection
/// never overlap and come in order: onOpen, onMessage*, onClose.
class WsHandler {
 public:
  virtual ~WsHandler() = default;
  /// The handshake completed; keep `connection` to send.
  virtual void onOpen(std::shared_ptr<WsConnection> connection) = 0;
  /// One complete frame (never larger than WsAccept::max_frame_bytes).
  virtual void onMessage(std::string data, bool binary) = 0;
  /// The connection ended (either side, or an error). No more calls follow.
  virtual void onClose() = 0;
};

/// The application's answer to an upgrade request.
struct WsAccept {
  /// Null refuses the upgrade: `refusal` is sent as the HTTP response.
  std::shared_ptr<WsHandler> handler;
  Response refusal;
  /// Echoed in Sec-WebSocket-Protocol when it is one of the items the client
  /// offered, compared whole (see ws_handshake.h); otherwise no subprotocol
  /// is selected, as RFC 6455 §4.2.2 asks.
  std::string subprotocol;
  /// Larger incoming frames close the connection with 1009 (message too big).
  size_t max_frame_bytes = 16u << 20;
  /// Bound of the send queue (see WsConnection::send).
  size_t max_send_queue_bytes = 8u << 20;
  /// SO_SNDBUF of the connection's socket; 0 = the system's, autotuned (up to
  /// megabytes). A small one keeps a stalled peer's backlog in the send queue,
  /// where the application sees and bounds it, rather than in the kernel.
  size_t socket_send_buffer_bytes = 0;
};

/// Implemented by the application. Methods run on the I/O threads and may be
/// called concurrently; they should not block for long.
class Service {
 public:
  virtual ~Service() = default;
  /// Answers a complete HTTP request (body read within the size limit).
  virtual Response handleHttp(Request& request, const Peer& peer) = 0;
  /// Decides on a WebSocket upgrade request; malformed ones (see
  /// ws_handshake.h) are refused before they get here.
  virtual WsAccept acceptWebSocket(const Request& request, const Peer& peer) = 0;
};

}  // namespace rmap::net
