#pragma once
/// @file viewer_stream.h
/// A subscriber of rmapd's viewer stream (/v1/stream/viewer) for the integration tests.

#include <gtest/gtest.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace rmap::testing {

namespace viewer_stream_detail {
namespace asio = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;

/// A viewer stream subscriber reading JSON frames with a deadline.
class ViewerStream {
 public:
  ViewerStream(uint16_t port, const std::string& map) : ws_(io_) {
    asio::ip::tcp::resolver resolver(io_);
    beast::get_lowest_layer(ws_).connect(resolver.resolve("127.0.0.1", std::to_string(port)));
    ws_.handshake("127.0.0.1:" + std::to_string(port), "/v1/stream/viewer?map=" + map);
  }

  /// The next frame, or nullopt when none arrives within `timeout`.
  std::optional<nlohmann::json> next(std::chrono::milliseconds timeout) {
    beast::flat_buffer buffer;
    bool done = false;
    beast::error_code error;
    ws_.async_read(buffer, [&](beast::error_code e, size_t) {
      error = e;
      done = true;
    });
    io_.restart();
    io_.run_for(timeout);
    if (!done) {
      beast::get_lowest_layer(ws_).cancel();
      io_.restart();
      io_.run();  // lets the cancelled read finish
      return std::nullopt;
    }
    if (error) throw beast::system_error(error);
    EXPECT_TRUE(ws_.got_text());
    return nlohmann::json::parse(beast::buffers_to_string(buffer.data()));
  }

 private:
  asio::io_context io_;
  websocket::stream<beast::tcp_stream> ws_;
};

}  // namespace viewer_stream_detail

using viewer_stream_detail::ViewerStream;

}  // namespace rmap::testing
