#include <gtest/gtest.h>

#include <stdexcept>

#include "beast_test_client.h"
#include "net/server.h"

namespace rmap::net::test {
namespace {

TEST(ServerLifecycle, PortZeroGivesARealPort) {
  Watchdog watchdog;
  LambdaService service;
  Server server(testOptions(), service);
  server.start();
  ASSERT_NE(server.port(), 0);
  HttpClient client(server.port());
  EXPECT_EQ(client.get("/").body(), "ok");
}

TEST(ServerLifecycle, BindFailureNamesTheAddress) {
  Watchdog watchdog;
  LambdaService service;
  Server taken(testOptions(), service);
  taken.start();
  ServerOptions options = testOptions();
  options.port = taken.port();
  Server second(options, service);
  try {
    second.start();
    FAIL() << "bound a port already listened on";
  } catch (const std::runtime_error& error) {
    EXPECT_EQ(std::string(error.what()).rfind("cannot listen on 127.0.0.1:" + std::to_string(taken.port()) + ": ", 0),
              0u)
        << error.what();
  }
}

TEST(ServerLifecycle, UnresolvableHostThrows) {
  Watchdog watchdog;
  LambdaService service;
  ServerOptions options = testOptions();
  options.host = "no-such-host.invalid";
  Server server(options, service);
  EXPECT_THROW(server.start(), std::runtime_error);
}

TEST(ServerLifecycle, ListensOnIpv6Loopback) {
  Watchdog watchdog;
  LambdaService service;
  Peer seen;
  service.http = [&](Request& request, const Peer& peer) {
    seen = peer;
    return Response{http::status::no_content, request.version()};
  };
  ServerOptions options = testOptions();
  options.host = "::1";
  Server server(options, service);
  try {
    server.start();
  } catch (const std::runtime_error& error) {
    GTEST_SKIP() << "no IPv6 loopback here: " << error.what();
  }
  asio::io_context io;
  tcp::socket socket(io);
  socket.connect({asio::ip::make_address("::1"), server.port()});
  http::write(socket, HttpClient::makeRequest(http::verb::get, "/"));
  beast::flat_buffer buffer;
  StringResponse response;
  http::read(socket, buffer, response);
  EXPECT_EQ(response.result(), http::status::no_content);
  EXPECT_TRUE(seen.loopback);
  EXPECT_EQ(seen.address, "::1");
}

TEST(ServerLifecycle, StopIsIdempotentAndClosesConnections) {
  Watchdog watchdog;
  LambdaService service;
  Server server(testOptions(), service);
  server.start();
  HttpClient client(server.port());
  EXPECT_EQ(client.get("/").result(), http::status::ok);
  EXPECT_EQ(server.connections(), 1u);
  server.stop();
  server.stop();
  EXPECT_TRUE(client.closedByServer());
  EXPECT_EQ(server.connections(), 0u);
  boost::system::error_code ec;
  asio::io_context io;
  tcp::socket late(io);
  late.connect(loopback(server.port()), ec);
  EXPECT_TRUE(ec) << "still accepting after stop";
}

TEST(ServerLifecycle, StopWithoutStartIsHarmless) {
  LambdaService service;
  Server server(testOptions(), service);
  server.stop();
  EXPECT_THROW(server.start(), std::logic_error);
}

TEST(ServerLifecycle, CountsConnections) {
  Watchdog watchdog;
  LambdaService service;
  Server server(testOptions(), service);
  server.start();
  {
    HttpClient a(server.port());
    HttpClient b(server.port());
    a.get("/");
    b.get("/");
    EXPECT_EQ(server.connections(), 2u);
    EXPECT_EQ(server.webSocketConnections(), 0u);
  }
  EXPECT_TRUE(eventually([&] { return server.connections() == 0; }));
}

}  // namespace
}  // namespace rmap::net::test
