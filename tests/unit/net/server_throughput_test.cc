#include <gtest/gtest.h>

#include <boost/asio/read.hpp>
#include <boost/asio/read_until.hpp>
#include <boost/asio/streambuf.hpp>
#include <atomic>
#include <cstdio>
#include <string_view>
#include <vector>

#include "beast_test_client.h"
#include "net/server.h"

namespace rmap::net::test {
namespace {

/// Reads one response whose head carries a Content-Length; returns its status line.
std::string readResponse(tcp::socket& socket, asio::streambuf& buffer) {
  const size_t head_bytes = asio::read_until(socket, buffer, "\r\n\r\n");
  const std::string_view data(static_cast<const char*>(buffer.data().data()), buffer.size());
  const std::string_view head = data.substr(0, head_bytes);
  const size_t field = head.find("Content-Length: ");
  const size_t body_bytes = field == std::string_view::npos ? 0 : std::stoul(std::string(head.substr(field + 16)));
  std::string status(head.substr(0, head.find("\r\n")));
  if (buffer.size() < head_bytes + body_bytes) asio::read(socket, buffer, asio::transfer_exactly(head_bytes + body_bytes - buffer.size()));
  buffer.consume(head_bytes + body_bytes);
  return status;
}

// A measurement, not a check: prints the rate of small keep-alive requests
// from 4 concurrent connections, each sending the next request once the
// previous answer arrived. Client and server share the machine's cores.
TEST(ServerThroughput, PrintsKeepAliveRequestsPerSecond) {
  Watchdog watchdog;
  LambdaService service;
  Server server(testOptions(), service);
  server.start();

  constexpr int kConnections = 4;
  constexpr auto kDuration = std::chrono::seconds(2);
  const std::string request = "GET /ping HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n";
  std::atomic<long> answered{0};
  std::atomic<long> wrong{0};
  const auto end = std::chrono::steady_clock::now() + kDuration;
  std::vector<std::thread> clients;
  for (int c = 0; c < kConnections; ++c) {
    clients.emplace_back([&] {
      asio::io_context io;
      tcp::socket socket(io);
      socket.connect(loopback(server.port()));
      socket.set_option(tcp::no_delay(true));
      asio::streambuf buffer;
      long count = 0;
      while (std::chrono::steady_clock::now() < end) {
        asio::write(socket, asio::buffer(request));
        if (readResponse(socket, buffer) != "HTTP/1.1 200 OK") ++wrong;
        ++count;
      }
      answered += count;
    });
  }
  for (auto& client : clients) client.join();
  const double seconds = std::chrono::duration<double>(kDuration).count();
  std::printf("[ rate     ] %.0f requests/s (%d keep-alive connections, %.0f s, 2 I/O threads)\n",
              answered.load() / seconds, kConnections, seconds);
  EXPECT_EQ(wrong.load(), 0);
  EXPECT_GT(answered.load(), 0);
}

}  // namespace
}  // namespace rmap::net::test
