#pragma once
/// @file beast_test_client.h
/// Blocking Boost.Beast clients and a lambda-driven Service for the net tests.
/// Blocking reads cannot time out, so every test also arms a Watchdog that
/// aborts the binary when it hangs.

#include <gtest/gtest.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core/buffers_to_string.hpp>
#include <boost/beast/core/flat_buffer.hpp>
#include <boost/beast/http/read.hpp>
#include <boost/beast/http/string_body.hpp>
#include <boost/beast/http/write.hpp>
#include <boost/beast/websocket/stream.hpp>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "net/server.h"

namespace rmap::net::test {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using namespace std::chrono_literals;

/// Aborts the process when not destroyed within `limit`: a hung test fails
/// fast instead of blocking the suite.
class Watchdog {
 public:
  explicit Watchdog(std::chrono::seconds limit = std::chrono::seconds(20))
      : thread_([this, limit] {
          std::unique_lock lock(mutex_);
          if (!cv_.wait_for(lock, limit, [this] { return done_; })) {
            std::fprintf(stderr, "net test watchdog: test exceeded %llds\n", static_cast<long long>(limit.count()));
            std::abort();
          }
        }) {}
  ~Watchdog() {
    {
      std::lock_guard lock(mutex_);
      done_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool done_ = false;
  std::thread thread_;
};

/// Polls `condition` until it holds or `timeout` passes.
template <class Condition>
bool eventually(Condition condition, std::chrono::milliseconds timeout = 3000ms) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!condition()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(2ms);
  }
  return true;
}

/// A Service whose answers are set per test.
class LambdaService : public Service {
 public:
  std::function<Response(Request&, const Peer&)> http = [](Request& request, const Peer&) {
    Response response{http::status::ok, request.version()};
    response.body() = "ok";
    return response;
  };
  std::function<WsAccept(const Request&, const Peer&)> ws = [](const Request&, const Peer&) {
    WsAccept refused;
    refused.refusal = Response{http::status::not_found, 11};
    return refused;
  };

  Response handleHttp(Request& request, const Peer& peer) override { return http(request, peer); }
  WsAccept acceptWebSocket(const Request& request, const Peer& peer) override { return ws(request, peer); }
};

/// Loopback, ephemeral port, two I/O threads.
inline ServerOptions testOptions() {
  ServerOptions options;
  options.host = "127.0.0.1";
  options.port = 0;
  options.io_threads = 2;
  return options;
}

inline tcp::endpoint loopback(uint16_t port) { return {asio::ip::make_address("127.0.0.1"), port}; }

using StringResponse = http::response<http::string_body>;

/// One blocking HTTP/1.1 connection.
class HttpClient {
 public:
  explicit HttpClient(uint16_t port) : socket_(io_) { socket_.connect(loopback(port)); }

  static Request makeRequest(http::verb method, const std::string& target, std::string body = {}) {
    Request request{method, target, 11};
    request.set(http::field::host, "127.0.0.1");
    request.body() = std::move(body);
    request.prepare_payload();
    return request;
  }

  void send(const Request& request) { http::write(socket_, request); }
  void writeRaw(const std::string& bytes) { asio::write(socket_, asio::buffer(bytes)); }

  StringResponse read() {
    StringResponse response;
    http::read(socket_, buffer_, response);
    return response;
  }

  /// The next response, or nullopt when none arrived within `timeout` (the
  /// socket is then closed): for answers a server might wrongly hold back.
  std::optional<StringResponse> readWithin(std::chrono::milliseconds timeout) {
    StringResponse response;
    boost::system::error_code ec;
    bool done = false;
    http::async_read(socket_, buffer_, response, [&](boost::system::error_code result, size_t) {
      ec = result;
      done = true;
    });
    io_.run_for(timeout);
    const bool timed_out = !done;
    if (timed_out) {
      socket_.close();
      io_.run();  // the read completes as aborted
    }
    io_.restart();
    if (timed_out || ec) return std::nullopt;
    return response;
  }

  StringResponse get(const std::string& target) {
    send(makeRequest(http::verb::get, target));
    return read();
  }

  /// Whether the server closed the connection: the next read ends with EOF
  /// (or a reset) instead of data.
  bool closedByServer() {
    char byte;
    boost::system::error_code ec;
    socket_.read_some(asio::buffer(&byte, 1), ec);
    return ec == asio::error::eof || ec == asio::error::connection_reset;
  }

  tcp::socket& socket() { return socket_; }

 private:
  asio::io_context io_;
  tcp::socket socket_;
  beast::flat_buffer buffer_;
};

/// One blocking WebSocket client connection.
class WsClient {
  asio::io_context io_;  // before ws, which uses it

 public:
  explicit WsClient(uint16_t port) : ws(io_) { ws.next_layer().connect(loopback(port)); }

  /// The opening handshake; `response` receives the server's answer.
  boost::system::error_code handshake(websocket::response_type& response, const std::string& subprotocols = {}) {
    if (!subprotocols.empty()) {
      ws.set_option(websocket::stream_base::decorator([subprotocols](websocket::request_type& request) {
        request.set(http::field::sec_websocket_protocol, subprotocols);
      }));
    }
    // Async because the blocking handshake of Boost 1.74 leaves `response`
    // empty when the upgrade is declined.
    boost::system::error_code ec;
    ws.async_handshake(response, "127.0.0.1", "/ws", [&ec](boost::system::error_code result) { ec = result; });
    io_.run();
    io_.restart();
    return ec;
  }

  void handshake() {
    websocket::response_type response;
    const auto ec = handshake(response);
    ASSERT_FALSE(ec) << ec.message();
  }

  void send(const std::string& data, bool binary) {
    ws.binary(binary);
    ws.write(asio::buffer(data));
  }

  /// The next message, and whether it was binary.
  std::pair<std::string, bool> read() {
    beast::flat_buffer buffer;
    ws.read(buffer);
    return {beast::buffers_to_string(buffer.data()), ws.got_binary()};
  }

  /// Reads until the connection ends; the error that ended it.
  boost::system::error_code readUntilClosed() {
    beast::flat_buffer buffer;
    boost::system::error_code ec;
    while (!ec) {
      ws.read(buffer, ec);
      buffer.clear();
    }
    return ec;
  }

  websocket::stream<tcp::socket> ws;
};

}  // namespace rmap::net::test
