#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "beast_test_client.h"
#include "net/server.h"

namespace rmap::net::test {
namespace {

/// A started server on a free loopback port around a LambdaService.
class ServerHttp : public ::testing::Test {
 protected:
  void start(ServerOptions options = testOptions()) {
    server_ = std::make_unique<Server>(options, service_);
    server_->start();
  }
  uint16_t port() const { return server_->port(); }

  Watchdog watchdog_;
  LambdaService service_;
  std::unique_ptr<Server> server_;
};

/// The error code of a JSON error body.
std::string errorCode(const StringResponse& response) {
  return nlohmann::json::parse(response.body()).at("error").at("code").get<std::string>();
}

TEST_F(ServerHttp, RequestReachesTheServiceWithPeer) {
  std::mutex mutex;
  Request seen;
  Peer seen_peer;
  service_.http = [&](Request& request, const Peer& peer) {
    std::lock_guard lock(mutex);
    seen = request;
    seen_peer = peer;
    Response response{http::status::created, request.version()};
    response.body() = "made " + request.body();
    return response;
  };
  start();
  HttpClient client(port());
  client.send(HttpClient::makeRequest(http::verb::post, "/maps/a?x=1", "hello"));
  const StringResponse response = client.read();

  EXPECT_EQ(response.result(), http::status::created);
  EXPECT_EQ(response.body(), "made hello");
  EXPECT_EQ(response[http::field::server], "rmapd");
  EXPECT_EQ(response[http::field::content_length], "10");
  std::lock_guard lock(mutex);
  EXPECT_EQ(seen.method(), http::verb::post);
  EXPECT_EQ(seen.target(), "/maps/a?x=1");
  EXPECT_EQ(seen.body(), "hello");
  EXPECT_TRUE(seen_peer.loopback);
  EXPECT_EQ(seen_peer.address, "127.0.0.1");
  EXPECT_EQ(seen_peer.port, client.socket().local_endpoint().port());
}

TEST_F(ServerHttp, KeepAliveServesSeveralRequestsOnOneConnection) {
  service_.http = [](Request& request, const Peer&) {
    Response response{http::status::ok, request.version()};
    response.body() = std::string(request.target());
    return response;
  };
  start();
  HttpClient client(port());
  for (int i = 0; i < 5; ++i) {
    const StringResponse response = client.get("/n/" + std::to_string(i));
    EXPECT_EQ(response.body(), "/n/" + std::to_string(i));
    EXPECT_TRUE(response.keep_alive());
  }
  EXPECT_EQ(server_->connections(), 1u);
}

TEST_F(ServerHttp, PipelinedRequestsAreAnsweredInOrder) {
  service_.http = [](Request& request, const Peer&) {
    // The first answer is the slowest: order must not follow completion time.
    if (request.target() == "/0") std::this_thread::sleep_for(50ms);
    Response response{http::status::ok, request.version()};
    response.body() = std::string(request.target());
    return response;
  };
  start();
  HttpClient client(port());
  std::string batch;
  for (int i = 0; i < 4; ++i) {
    batch += "GET /" + std::to_string(i) + " HTTP/1.1\r\nHost: x\r\n\r\n";
  }
  client.writeRaw(batch);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(client.read().body(), "/" + std::to_string(i));
}

TEST_F(ServerHttp, BodyOverTheLimitGets413AndClose) {
  std::atomic<int> calls{0};
  service_.http = [&](Request& request, const Peer&) {
    ++calls;
    return Response{http::status::ok, request.version()};
  };
  ServerOptions options = testOptions();
  options.max_body_bytes = 1024;
  start(options);
  HttpClient client(port());
  client.send(HttpClient::makeRequest(http::verb::post, "/ingest", std::string(1025, 'x')));
  const StringResponse response = client.read();
  EXPECT_EQ(response.result(), http::status::payload_too_large);
  EXPECT_EQ(response[http::field::content_type], "application/json");
  EXPECT_EQ(errorCode(response), "payload_too_large");
  EXPECT_FALSE(response.keep_alive());
  EXPECT_TRUE(client.closedByServer());
  EXPECT_EQ(calls.load(), 0);

  HttpClient at_limit(port());
  at_limit.send(HttpClient::makeRequest(http::verb::post, "/ingest", std::string(1024, 'x')));
  EXPECT_EQ(at_limit.read().result(), http::status::ok);
  EXPECT_EQ(calls.load(), 1);
}

TEST_F(ServerHttp, ClientStillSendingAHugeBodyReadsThe413) {
  ServerOptions options = testOptions();
  options.max_body_bytes = 1024;
  start(options);
  HttpClient client(port());
  // Far more than the socket buffers hold: the write completes only if the
  // server keeps reading after it answered.
  client.send(HttpClient::makeRequest(http::verb::post, "/ingest", std::string(16u << 20, 'x')));
  const StringResponse response = client.read();
  EXPECT_EQ(response.result(), http::status::payload_too_large);
  EXPECT_EQ(errorCode(response), "payload_too_large");
}

TEST_F(ServerHttp, HeaderOverTheLimitGets431) {
  ServerOptions options = testOptions();
  options.max_header_bytes = 1024;
  start(options);
  HttpClient client(port());
  client.writeRaw("GET / HTTP/1.1\r\nHost: x\r\nX-Big: " + std::string(2000, 'a') + "\r\n\r\n");
  const StringResponse response = client.read();
  EXPECT_EQ(response.result(), http::status::request_header_fields_too_large);
  EXPECT_EQ(errorCode(response), "header_too_large");
  EXPECT_TRUE(client.closedByServer());
}

TEST_F(ServerHttp, GarbageGets400AndClose) {
  start();
  HttpClient client(port());
  client.writeRaw("\x16\x03\x01 this is not http\r\n\r\n");
  const StringResponse response = client.read();
  EXPECT_EQ(response.result(), http::status::bad_request);
  EXPECT_EQ(response[http::field::content_type], "application/json");
  EXPECT_EQ(errorCode(response), "bad_request");
  EXPECT_TRUE(client.closedByServer());
}

TEST_F(ServerHttp, ServiceThrowingGets500AndTheConnectionSurvives) {
  service_.http = [](Request& request, const Peer&) {
    if (request.target() == "/throw") throw std::runtime_error("secret detail");
    Response response{http::status::ok, request.version()};
    response.body() = "fine";
    return response;
  };
  start();
  HttpClient client(port());
  const StringResponse failed = client.get("/throw");
  EXPECT_EQ(failed.result(), http::status::internal_server_error);
  EXPECT_EQ(errorCode(failed), "internal_error");
  EXPECT_EQ(failed.body().find("secret"), std::string::npos);
  EXPECT_TRUE(failed.keep_alive());
  const StringResponse next = client.get("/ok");
  EXPECT_EQ(next.result(), http::status::ok);
  EXPECT_EQ(next.body(), "fine");
}

TEST_F(ServerHttp, ConnectionCloseIsHonoured) {
  start();
  HttpClient client(port());
  Request request = HttpClient::makeRequest(http::verb::get, "/");
  request.keep_alive(false);
  client.send(request);
  const StringResponse response = client.read();
  EXPECT_EQ(response.result(), http::status::ok);
  EXPECT_FALSE(response.keep_alive());
  EXPECT_TRUE(client.closedByServer());
}

TEST_F(ServerHttp, ServiceHeadersAndFramingAreKept) {
  service_.http = [](Request& request, const Peer&) {
    Response response{http::status::ok, request.version()};
    response.set(http::field::server, "custom");
    response.content_length(42);  // a HEAD answer: the length of the omitted body
    return response;
  };
  start();
  HttpClient client(port());
  client.send(HttpClient::makeRequest(http::verb::head, "/tile"));
  http::response_parser<http::empty_body> parser;
  parser.skip(true);  // HEAD: no body follows the Content-Length
  beast::flat_buffer buffer;
  http::read(client.socket(), buffer, parser);
  EXPECT_EQ(parser.get()[http::field::server], "custom");
  EXPECT_EQ(parser.get()[http::field::content_length], "42");
}

TEST_F(ServerHttp, IdleConnectionsAreClosed) {
  ServerOptions options = testOptions();
  options.idle_timeout = std::chrono::seconds(1);
  start(options);
  HttpClient client(port());
  EXPECT_EQ(client.get("/").result(), http::status::ok);
  const auto begin = std::chrono::steady_clock::now();
  EXPECT_TRUE(client.closedByServer());
  EXPECT_LT(std::chrono::steady_clock::now() - begin, 3s);
  EXPECT_TRUE(eventually([&] { return server_->connections() == 0; }));
}

TEST_F(ServerHttp, ConnectionsOverTheLimitAreClosedAtOnce) {
  ServerOptions options = testOptions();
  options.max_connections = 1;
  start(options);
  HttpClient first(port());
  EXPECT_EQ(first.get("/").result(), http::status::ok);
  HttpClient second(port());
  EXPECT_TRUE(second.closedByServer());
  EXPECT_EQ(first.get("/").result(), http::status::ok);
  EXPECT_EQ(server_->connections(), 1u);
}

TEST_F(ServerHttp, ExpectContinueGets100BeforeTheBodyIsSent) {
  service_.http = [](Request& request, const Peer&) {
    Response response{http::status::ok, request.version()};
    response.body() = "got " + request.body();
    return response;
  };
  start();
  HttpClient client(port());
  client.writeRaw("POST /ingest HTTP/1.1\r\nHost: x\r\nExpect: 100-continue\r\nContent-Length: 5\r\n\r\n");
  const auto interim = client.readWithin(2000ms);
  ASSERT_TRUE(interim) << "no 100 Continue: the server waits for a body the client holds back";
  EXPECT_EQ(interim->result(), http::status::continue_);
  client.writeRaw("hello");
  const StringResponse response = client.read();
  EXPECT_EQ(response.result(), http::status::ok);
  EXPECT_EQ(response.body(), "got hello");
  EXPECT_TRUE(response.keep_alive());
  EXPECT_EQ(client.get("/next").result(), http::status::ok);  // the connection goes on
}

TEST_F(ServerHttp, ExpectContinueOverTheLimitGets413WithoutTheBody) {
  std::atomic<int> calls{0};
  service_.http = [&](Request& request, const Peer&) {
    ++calls;
    return Response{http::status::ok, request.version()};
  };
  ServerOptions options = testOptions();
  options.max_body_bytes = 1024;
  start(options);
  HttpClient client(port());
  client.writeRaw("POST /ingest HTTP/1.1\r\nHost: x\r\nExpect: 100-continue\r\nContent-Length: 1025\r\n\r\n");
  const auto response = client.readWithin(2000ms);
  ASSERT_TRUE(response);
  EXPECT_EQ(response->result(), http::status::payload_too_large);
  EXPECT_EQ(errorCode(*response), "payload_too_large");
  EXPECT_EQ(calls.load(), 0);
}

TEST_F(ServerHttp, ExpectContinueWithoutABodyIsServedAtOnce) {
  start();
  HttpClient client(port());
  client.writeRaw("POST /x HTTP/1.1\r\nHost: x\r\nExpect: 100-continue\r\nContent-Length: 0\r\n\r\n");
  EXPECT_EQ(client.read().result(), http::status::ok);  // no interim answer first
}

TEST_F(ServerHttp, UnknownExpectationGets417) {
  start();
  HttpClient client(port());
  client.writeRaw("POST /x HTTP/1.1\r\nHost: x\r\nExpect: teapot\r\nContent-Length: 1\r\n\r\nx");
  const StringResponse response = client.read();
  EXPECT_EQ(response.result(), http::status::expectation_failed);
  EXPECT_EQ(errorCode(response), "expectation_failed");
  EXPECT_TRUE(client.closedByServer());
}

/// Sends `head`, whose framing the server must refuse, followed by a request
/// that would be served if the server misjudged where the first one ends.
class SmugglingTest : public ServerHttp {
 protected:
  void SetUp() override {
    service_.http = [this](Request& request, const Peer&) {
      std::lock_guard lock(mutex_);
      targets_.emplace_back(request.target());
      return Response{http::status::ok, request.version()};
    };
    ServerOptions options = testOptions();
    options.idle_timeout = std::chrono::seconds(1);  // a server that keeps the connection open fails, not hangs
    start(options);
  }
  StringResponse send(const std::string& head, const std::string& body) {
    HttpClient client(port());
    client.writeRaw(head + body);
    StringResponse response = client.read();
    EXPECT_TRUE(client.closedByServer());
    return response;
  }
  std::vector<std::string> targets() {
    std::lock_guard lock(mutex_);
    return targets_;
  }

  const std::string smuggled_ = "GET /smuggled HTTP/1.1\r\nHost: x\r\n\r\n";

 private:
  std::mutex mutex_;
  std::vector<std::string> targets_;
};

TEST_F(SmugglingTest, TransferEncodingNotEndingInChunkedIs400) {
  for (const char* coding : {"gzip", "chunked, gzip", "xchunked"}) {
    const StringResponse response = send(
        "POST /a HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: " + std::string(coding) + "\r\n\r\n", smuggled_);
    EXPECT_EQ(response.result(), http::status::bad_request) << coding;
  }
  EXPECT_TRUE(targets().empty());
}

TEST_F(SmugglingTest, ContentLengthNextToTransferEncodingIs400) {
  const std::string chunked_body = "0\r\n\r\n";
  const StringResponse response =
      send("POST /a HTTP/1.1\r\nHost: x\r\nContent-Length: " + std::to_string(chunked_body.size() + smuggled_.size()) +
               "\r\nTransfer-Encoding: chunked\r\n\r\n",
           chunked_body + smuggled_);
  EXPECT_EQ(response.result(), http::status::bad_request);
  const StringResponse reversed =
      send("POST /a HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\nContent-Length: 3\r\n\r\n",
           chunked_body + smuggled_);
  EXPECT_EQ(reversed.result(), http::status::bad_request);
  const StringResponse conflicting =
      send("POST /a HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\nContent-Length: 38\r\n\r\n", smuggled_);
  EXPECT_EQ(conflicting.result(), http::status::bad_request);
  EXPECT_TRUE(targets().empty());
}

TEST_F(SmugglingTest, TransferEncodingInHttp10Is400) {
  const StringResponse response =
      send("POST /a HTTP/1.0\r\nHost: x\r\nConnection: keep-alive\r\nTransfer-Encoding: chunked\r\n\r\n",
           "0\r\n\r\n" + smuggled_);
  EXPECT_EQ(response.result(), http::status::bad_request);
  EXPECT_TRUE(targets().empty());
}

TEST_F(SmugglingTest, CodingsOtherThanChunkedGet501) {
  const StringResponse response =
      send("POST /a HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: gzip, chunked\r\n\r\n", "0\r\n\r\n");
  EXPECT_EQ(response.result(), http::status::not_implemented);
  EXPECT_EQ(errorCode(response), "not_implemented");
  EXPECT_TRUE(targets().empty());
}

TEST_F(SmugglingTest, ChunkedBodiesAreServed) {
  HttpClient client(port());
  client.writeRaw("POST /a HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n3\r\nabc\r\n0\r\n\r\n");
  EXPECT_EQ(client.read().result(), http::status::ok);
  EXPECT_EQ(client.get("/b").result(), http::status::ok);
  EXPECT_EQ(targets(), (std::vector<std::string>{"/a", "/b"}));
}

TEST_F(SmugglingTest, Http11NeedsExactlyOneHost) {
  EXPECT_EQ(send("GET /a HTTP/1.1\r\n\r\n", "").result(), http::status::bad_request);
  EXPECT_EQ(send("GET /a HTTP/1.1\r\nHost: x\r\nHost: y\r\n\r\n", "").result(), http::status::bad_request);
  EXPECT_TRUE(targets().empty());
  HttpClient old(port());
  old.writeRaw("GET /old HTTP/1.0\r\n\r\n");  // HTTP/1.0 may omit it
  EXPECT_EQ(old.read().result(), http::status::ok);
}

TEST_F(ServerHttp, SlowHeaderIsCutAtTheIdleTimeout) {
  ServerOptions options = testOptions();
  options.idle_timeout = std::chrono::seconds(1);
  start(options);
  HttpClient client(port());
  const auto begin = std::chrono::steady_clock::now();
  // A byte every 200 ms keeps the connection busy, never idle: the request
  // as a whole must still arrive within the timeout.
  const std::string head = "GET / HTTP/1.1\r\nHost: x\r\nX-Slow: aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa";
  boost::system::error_code ec;
  for (size_t i = 0; i < head.size() && !ec; ++i) {
    asio::write(client.socket(), asio::buffer(&head[i], 1), ec);
    std::this_thread::sleep_for(200ms);
  }
  EXPECT_TRUE(ec || client.closedByServer());
  EXPECT_LT(std::chrono::steady_clock::now() - begin, 3s);
  EXPECT_TRUE(eventually([&] { return server_->connections() == 0; }));
}

}  // namespace
}  // namespace rmap::net::test
