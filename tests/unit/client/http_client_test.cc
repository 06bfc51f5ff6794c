#include "client/http_client.h"

#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>

#include "client/robot_client.h"
#include "fake_http_server.h"

namespace rmap::client {
namespace {

using std::chrono::milliseconds;
using Clock = std::chrono::steady_clock;
using test::FakeHttpServer;

TEST(HttpClient, GetAndPost) {
  FakeHttpServer server;
  HttpClient http(server.url(), "viewer-1");

  const HttpResponse hello = http.get("/hello", {{"X-Trace", "abc"}});
  EXPECT_EQ(hello.status, 200);
  EXPECT_EQ(hello.body, "hello");
  EXPECT_EQ(hello.header("content-type"), "text/plain");
  EXPECT_EQ(hello.header("x-authorization"), "Bearer viewer-1");
  EXPECT_EQ(hello.header("no-such-header"), "");

  const std::string body("\x08\x01\x00\x7f binary", 12);
  const HttpResponse echo = http.post("/echo", body, "application/x-protobuf");
  EXPECT_EQ(echo.status, 200);
  EXPECT_EQ(echo.body, body);
  EXPECT_EQ(echo.header("content-type"), "application/x-protobuf");
}

TEST(HttpClient, HttpErrorsAreReturnedNotThrown) {
  FakeHttpServer server;
  HttpClient http(server.url());
  const HttpResponse missing = http.get("/nowhere");
  EXPECT_EQ(missing.status, 404);
  EXPECT_NE(missing.body.find("not_found"), std::string::npos);
  EXPECT_EQ(missing.header("x-authorization"), "");  // no token, no header
}

TEST(HttpClient, LargeBodiesRoundTrip) {
  FakeHttpServer server;
  HttpClient http(server.url());
  std::string body(3u << 20, '\0');
  for (size_t i = 0; i < body.size(); ++i) body[i] = static_cast<char>(i * 131 % 251);
  const HttpResponse echo = http.post("/echo", body, "application/octet-stream");
  ASSERT_EQ(echo.status, 200);
  EXPECT_EQ(echo.body.size(), body.size());
  EXPECT_TRUE(echo.body == body);
}

TEST(HttpClient, KeepAliveReusesOneConnection) {
  FakeHttpServer server;
  HttpClient http(server.url());
  for (int i = 0; i < 5; ++i) {
    const HttpResponse r = i % 2 ? http.post("/echo", "x", "text/plain") : http.get("/hello");
    ASSERT_EQ(r.status, 200);
    EXPECT_EQ(r.header("x-connection"), "1");
  }
  EXPECT_EQ(server.acceptedConnections(), 1);
}

TEST(HttpClient, ReconnectsWhenTheServerDroppedTheConnection) {
  FakeHttpServer server(FakeHttpServer::AfterResponse::drop);
  HttpClient http(server.url());
  for (int i = 1; i <= 3; ++i) {
    const HttpResponse r = http.get("/hello");
    ASSERT_EQ(r.status, 200);
    EXPECT_EQ(r.header("x-connection"), std::to_string(i));
  }
  EXPECT_EQ(server.acceptedConnections(), 3);
}

TEST(HttpClient, FollowsConnectionClose) {
  FakeHttpServer server(FakeHttpServer::AfterResponse::announce_close);
  HttpClient http(server.url());
  for (int i = 1; i <= 3; ++i) {
    const HttpResponse r = http.post("/echo", "abc", "text/plain");
    ASSERT_EQ(r.status, 200);
    EXPECT_EQ(r.body, "abc");
    EXPECT_EQ(r.header("connection"), "close");
  }
  EXPECT_EQ(server.acceptedConnections(), 3);
}

TEST(HttpClient, TimesOutOnASilentServer) {
  boost::asio::io_context ioc;
  // Listening but never accepting: the kernel completes the handshake, nobody answers.
  boost::asio::ip::tcp::acceptor silent(ioc, {boost::asio::ip::make_address("127.0.0.1"), 0});
  HttpClient http("http://127.0.0.1:" + std::to_string(silent.local_endpoint().port()), {}, milliseconds(200));
  const auto start = Clock::now();
  try {
    http.get("/hello");
    FAIL() << "answered";
  } catch (const ClientError& e) {
    EXPECT_NE(std::string(e.what()).find("timed out"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("GET /hello"), std::string::npos) << e.what();
  }
  const double elapsed_s = std::chrono::duration<double>(Clock::now() - start).count();
  EXPECT_GE(elapsed_s, 0.19);
  EXPECT_LT(elapsed_s, 2.0);
}

TEST(HttpClient, ConnectionFailuresAndBadUrlsThrow) {
  uint16_t port = 0;
  {  // a port nobody listens on any more
    boost::asio::io_context ioc;
    boost::asio::ip::tcp::acceptor acceptor(ioc, {boost::asio::ip::make_address("127.0.0.1"), 0});
    port = acceptor.local_endpoint().port();
  }
  HttpClient http("http://127.0.0.1:" + std::to_string(port));
  EXPECT_THROW(http.get("/hello"), ClientError);
  HttpClient https("https://127.0.0.1:" + std::to_string(port));
  EXPECT_THROW(https.get("/hello"), ClientError);
  try {
    HttpClient("https://127.0.0.1:1", {}, std::chrono::milliseconds(1000), "/nonexistent/ca.pem");
    ADD_FAILURE() << "a missing CA file was accepted";
  } catch (const ClientError& e) {
    EXPECT_NE(std::string(e.what()).find("CA file '/nonexistent/ca.pem'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(HttpClient("127.0.0.1:80"), ClientError);
}

}  // namespace
}  // namespace rmap::client
