#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <vector>

#include "beast_test_client.h"
#include "net/json_error.h"
#include "net/server.h"

namespace rmap::net::test {
namespace {

using Message = std::pair<std::string, bool>;

/// Records the calls of one connection, checks they never overlap, and runs
/// the behaviour a test sets in `on_message`.
class Recorder : public WsHandler {
 public:
  std::function<void(WsConnection&, const std::string&, bool)> on_message;

  void onOpen(std::shared_ptr<WsConnection> connection) override {
    Guard guard(*this);
    std::lock_guard lock(mutex_);
    if (closes_ > 0 || !messages_.empty()) ++misordered_;
    connection_ = std::move(connection);
    ++opens_;
  }
  void onMessage(std::string data, bool binary) override {
    Guard guard(*this);
    std::shared_ptr<WsConnection> connection;
    {
      std::lock_guard lock(mutex_);
      if (opens_ != 1 || closes_ > 0) ++misordered_;
      messages_.emplace_back(data, binary);
      connection = connection_;
    }
    if (on_message) on_message(*connection, data, binary);
  }
  void onClose() override {
    Guard guard(*this);
    std::lock_guard lock(mutex_);
    if (opens_ != 1) ++misordered_;
    ++closes_;
  }

  std::shared_ptr<WsConnection> connection() {
    std::lock_guard lock(mutex_);
    return connection_;
  }
  std::vector<Message> messages() {
    std::lock_guard lock(mutex_);
    return messages_;
  }
  int closes() {
    std::lock_guard lock(mutex_);
    return closes_;
  }
  /// Calls out of order (anything before onOpen, after onClose) or overlapping.
  int violations() {
    std::lock_guard lock(mutex_);
    return misordered_ + overlaps_.load();
  }

 private:
  /// Counts a call that starts while another one runs.
  struct Guard {
    explicit Guard(Recorder& recorder) : recorder_(recorder) {
      if (recorder_.in_call_.exchange(true)) ++recorder_.overlaps_;
    }
    ~Guard() { recorder_.in_call_ = false; }
    Recorder& recorder_;
  };

  std::atomic<bool> in_call_{false};
  std::atomic<int> overlaps_{0};
  std::mutex mutex_;
  std::shared_ptr<WsConnection> connection_;
  std::vector<Message> messages_;
  int opens_ = 0;
  int closes_ = 0;
  int misordered_ = 0;
};

void echo(WsConnection& connection, const std::string& data, bool binary) { connection.send(data, binary); }

/// A server accepting every upgrade with a fresh Recorder made like `accept_`.
class ServerWebSocket : public ::testing::Test {
 protected:
  void SetUp() override {
    service_.ws = [this](const Request&, const Peer&) {
      auto recorder = std::make_shared<Recorder>();
      recorder->on_message = on_message_;
      std::lock_guard lock(mutex_);
      recorders_.push_back(recorder);
      WsAccept accept = accept_;
      accept.handler = recorder;
      return accept;
    };
  }
  void start(ServerOptions options = testOptions()) {
    server_ = std::make_unique<Server>(options, service_);
    server_->start();
  }
  uint16_t port() const { return server_->port(); }
  std::shared_ptr<Recorder> recorder(size_t index) {
    std::lock_guard lock(mutex_);
    return recorders_.at(index);
  }
  std::shared_ptr<WsConnection> openedConnection(size_t index) {
    std::shared_ptr<WsConnection> connection;
    EXPECT_TRUE(eventually([&] {
      std::lock_guard lock(mutex_);
      return recorders_.size() > index && (connection = recorders_[index]->connection());
    }));
    return connection;
  }

  Watchdog watchdog_;
  LambdaService service_;
  WsAccept accept_;
  std::function<void(WsConnection&, const std::string&, bool)> on_message_;
  std::mutex mutex_;
  std::vector<std::shared_ptr<Recorder>> recorders_;
  std::unique_ptr<Server> server_;
};

TEST_F(ServerWebSocket, EchoesBinaryAndTextInOrder) {
  on_message_ = echo;
  start();
  WsClient client(port());
  client.handshake();
  client.send("hello", false);
  client.send(std::string("\0\1\2", 3), true);
  EXPECT_EQ(client.read(), Message("hello", false));
  EXPECT_EQ(client.read(), Message(std::string("\0\1\2", 3), true));
  for (int i = 0; i < 200; ++i) client.send(std::to_string(i), false);
  for (int i = 0; i < 200; ++i) ASSERT_EQ(client.read().first, std::to_string(i));
  EXPECT_EQ(recorder(0)->messages().size(), 202u);
  EXPECT_EQ(recorder(0)->violations(), 0);
}

TEST_F(ServerWebSocket, SubprotocolIsEchoed) {
  std::mutex offered_mutex;
  std::string offered;
  service_.ws = [&, accept_all = service_.ws](const Request& request, const Peer& peer) {
    std::lock_guard lock(offered_mutex);
    offered = std::string(request[http::field::sec_websocket_protocol]);
    return accept_all(request, peer);
  };
  accept_.subprotocol = "rmap.v1";
  start();
  WsClient client(port());
  websocket::response_type response;
  ASSERT_FALSE(client.handshake(response, "rmap.v1, bearer.abc"));
  {
    std::lock_guard lock(offered_mutex);
    EXPECT_EQ(offered, "rmap.v1, bearer.abc");
  }
  EXPECT_EQ(response[http::field::sec_websocket_protocol], "rmap.v1");
  EXPECT_EQ(response[http::field::server], "rmapd");
}

TEST_F(ServerWebSocket, SubprotocolIsEchoedOnlyWhenOfferedWhole) {
  accept_.subprotocol = "rmap.v1";
  start();
  for (const std::string offer : {"rmap.v1x, bearer.abc", "bearer.rmap.v1", "xrmap.v1", "rmap.v1.2"}) {
    WsClient client(port());
    websocket::response_type response;
    ASSERT_FALSE(client.handshake(response, offer));
    EXPECT_EQ(response.count(http::field::sec_websocket_protocol), 0u) << offer;
  }
  WsClient spaced(port());
  websocket::response_type response;
  ASSERT_FALSE(spaced.handshake(response, "bearer.abc ,\trmap.v1 "));
  EXPECT_EQ(response[http::field::sec_websocket_protocol], "rmap.v1");
}

TEST_F(ServerWebSocket, MalformedUpgradesAreRefusedBeforeTheService) {
  std::atomic<int> asked{0};
  service_.ws = [&, accept_all = service_.ws](const Request& request, const Peer& peer) {
    ++asked;
    return accept_all(request, peer);
  };
  start();
  const std::string upgrade = "GET /ws HTTP/1.1\r\nHost: x\r\nConnection: Upgrade\r\nUpgrade: websocket\r\n";
  const std::string key = "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n";
  const auto answer = [&](const std::string& fields) {
    HttpClient client(port());
    client.writeRaw(upgrade + fields + "\r\n");
    return client.read();
  };
  for (const std::string bad_key : {"", "Sec-WebSocket-Key: short==\r\n",
                                    "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25j!!==\r\n"}) {
    const StringResponse response = answer(bad_key + "Sec-WebSocket-Version: 13\r\n");
    EXPECT_EQ(response.result(), http::status::bad_request) << bad_key;
    EXPECT_EQ(response[http::field::content_type], "application/json");
  }
  const StringResponse old_version = answer(key + "Sec-WebSocket-Version: 8\r\n");
  EXPECT_EQ(old_version.result(), http::status::upgrade_required);
  EXPECT_EQ(old_version[http::field::sec_websocket_version], "13");
  EXPECT_EQ(answer(key).result(), http::status::upgrade_required);
  EXPECT_EQ(asked.load(), 0);
  EXPECT_EQ(answer(key + "Sec-WebSocket-Version: 13\r\n").result(), http::status::switching_protocols);
  EXPECT_EQ(asked.load(), 1);
}

TEST_F(ServerWebSocket, RefusalIsAFailedHandshakeWithItsStatus) {
  service_.ws = [](const Request& request, const Peer&) {
    WsAccept refused;
    refused.refusal =
        jsonError(http::status::unauthorized, "unauthorized", "token required", request.version(), true);
    return refused;
  };
  start();
  WsClient client(port());
  websocket::response_type response;
  EXPECT_EQ(client.handshake(response), websocket::error::upgrade_declined);
  EXPECT_EQ(response.result(), http::status::unauthorized);
  EXPECT_EQ(nlohmann::json::parse(response.body())["error"]["code"], "unauthorized");
  EXPECT_EQ(server_->webSocketConnections(), 0u);
}

TEST_F(ServerWebSocket, MessageOverTheLimitClosesWith1009) {
  on_message_ = echo;
  accept_.max_frame_bytes = 1024;
  start();
  WsClient client(port());
  client.handshake();
  client.send(std::string(1024, 'a'), true);
  EXPECT_EQ(client.read().first.size(), 1024u);
  client.send(std::string(1025, 'b'), true);
  EXPECT_EQ(client.readUntilClosed(), websocket::error::closed);
  EXPECT_EQ(client.ws.reason().code, websocket::close_code::too_big);
  EXPECT_TRUE(eventually([&] { return recorder(0)->closes() == 1; }));
  EXPECT_EQ(recorder(0)->messages().size(), 1u);
}

TEST_F(ServerWebSocket, FrameClaimingAHugeLengthIsRefusedFromItsHeader) {
  accept_.max_frame_bytes = 1024;
  start();
  WsClient client(port());
  client.handshake();
  // A masked binary frame announcing 2^40 bytes, none of which follow: the
  // server must answer from the header, neither waiting nor allocating.
  std::string header = {'\x82', '\xff'};
  for (int shift = 56; shift >= 0; shift -= 8) header += static_cast<char>((uint64_t{1} << 40) >> shift);
  header += std::string("\x01\x02\x03\x04", 4);
  asio::write(client.ws.next_layer(), asio::buffer(header));
  EXPECT_EQ(client.readUntilClosed(), websocket::error::closed);
  EXPECT_EQ(client.ws.reason().code, websocket::close_code::too_big);
  EXPECT_TRUE(eventually([&] { return recorder(0)->closes() == 1; }));
}

TEST_F(ServerWebSocket, OnCloseOnceWhenTheClientVanishesMidStream) {
  start();
  {
    WsClient client(port());
    client.handshake();
    for (int i = 0; i < 50; ++i) client.send(std::to_string(i), false);
    client.ws.next_layer().close();  // no close handshake
  }
  const auto handler = recorder(0);
  EXPECT_TRUE(eventually([&] { return handler->closes() == 1; }));
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(handler->closes(), 1);
  EXPECT_EQ(handler->violations(), 0);
  const auto messages = handler->messages();
  for (size_t i = 0; i < messages.size(); ++i) EXPECT_EQ(messages[i].first, std::to_string(i));
  EXPECT_TRUE(eventually([&] { return server_->webSocketConnections() == 0 && server_->connections() == 0; }));
}

TEST_F(ServerWebSocket, CloseFromTheHandlerFollowsTheQueuedFrames) {
  on_message_ = [](WsConnection& connection, const std::string&, bool) {
    EXPECT_TRUE(connection.send("x", false));
    EXPECT_TRUE(connection.send("y", true));
    connection.close(4000, "done");
    EXPECT_FALSE(connection.send("z", false));
  };
  start();
  WsClient client(port());
  client.handshake();
  client.send("bye", false);
  EXPECT_EQ(client.read(), Message("x", false));
  EXPECT_EQ(client.read(), Message("y", true));
  EXPECT_EQ(client.readUntilClosed(), websocket::error::closed);
  EXPECT_EQ(client.ws.reason().code, 4000);
  EXPECT_EQ(client.ws.reason().reason, "done");
  EXPECT_TRUE(eventually([&] { return recorder(0)->closes() == 1; }));
}

TEST_F(ServerWebSocket, HandlerExceptionClosesWith1011) {
  on_message_ = [](WsConnection&, const std::string&, bool) { throw std::runtime_error("handler bug"); };
  start();
  WsClient client(port());
  client.handshake();
  client.send("boom", false);
  EXPECT_EQ(client.readUntilClosed(), websocket::error::closed);
  EXPECT_EQ(client.ws.reason().code, websocket::close_code::internal_error);
  EXPECT_TRUE(eventually([&] { return recorder(0)->closes() == 1; }));
}

TEST_F(ServerWebSocket, SendQueueIsBoundedWhileOthersAreServed) {
  constexpr size_t kBound = 1u << 20;
  accept_.max_send_queue_bytes = kBound;
  on_message_ = echo;
  start();
  WsClient silent(port());  // never reads
  silent.handshake();
  const auto connection = openedConnection(0);
  ASSERT_TRUE(connection);
  const std::string frame(64u << 10, 'f');
  bool refused = false;
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  while (!refused && std::chrono::steady_clock::now() < deadline) {
    refused = !connection->send(frame, true);
    EXPECT_LE(connection->queuedBytes(), kBound);
  }
  ASSERT_TRUE(refused) << "the queue never filled";
  EXPECT_GT(connection->queuedBytes(), kBound - frame.size());

  HttpClient other(port());
  EXPECT_EQ(other.get("/").result(), http::status::ok);
  WsClient echo_client(port());
  echo_client.handshake();
  echo_client.send("still here", false);
  EXPECT_EQ(echo_client.read().first, "still here");

  EXPECT_EQ(server_->webSocketConnections(), 2u);  // the refused send kept the connection
  EXPECT_EQ(recorder(0)->closes(), 0);
}

TEST_F(ServerWebSocket, PauseReadingHoldsDeliveryUntilResumed) {
  on_message_ = [](WsConnection& connection, const std::string& data, bool) {
    if (data == "pause") connection.pauseReading(true);
  };
  start();
  WsClient client(port());
  client.handshake();
  client.send("pause", false);
  client.send("a", false);
  client.send("b", false);
  const auto handler = recorder(0);
  ASSERT_TRUE(eventually([&] { return !handler->messages().empty(); }));
  std::this_thread::sleep_for(300ms);
  EXPECT_EQ(handler->messages().size(), 1u);

  handler->connection()->pauseReading(false);  // from a foreign thread
  ASSERT_TRUE(eventually([&] { return handler->messages().size() == 3; }));
  EXPECT_EQ(handler->messages()[1].first, "a");
  EXPECT_EQ(handler->messages()[2].first, "b");
  EXPECT_EQ(handler->violations(), 0);
}

TEST_F(ServerWebSocket, StopIsPromptAndDetachesHeldConnections) {
  on_message_ = echo;
  start();
  std::vector<std::unique_ptr<WsClient>> clients;
  for (size_t i = 0; i < 3; ++i) {
    clients.push_back(std::make_unique<WsClient>(port()));
    clients.back()->handshake();
  }
  HttpClient keep_alive(port());
  EXPECT_EQ(keep_alive.get("/").result(), http::status::ok);
  std::vector<std::shared_ptr<WsConnection>> held;
  for (size_t i = 0; i < 3; ++i) held.push_back(openedConnection(i));
  clients[0]->send("in flight", false);
  EXPECT_EQ(server_->webSocketConnections(), 3u);

  const auto begin = std::chrono::steady_clock::now();
  server_->stop();
  EXPECT_LT(std::chrono::steady_clock::now() - begin, 2s);

  EXPECT_EQ(server_->webSocketConnections(), 0u);
  EXPECT_EQ(server_->connections(), 0u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(recorder(i)->closes(), 1);
    EXPECT_EQ(recorder(i)->violations(), 0);
    EXPECT_FALSE(held[i]->send("late", false));
    EXPECT_EQ(held[i]->queuedBytes(), 0u);
    EXPECT_TRUE(clients[i]->readUntilClosed());
  }
  EXPECT_TRUE(keep_alive.closedByServer());

  server_.reset();  // the held connections outlive the server
  held[0]->pauseReading(false);
  held[0]->close(1000, "gone");
  EXPECT_FALSE(held[0]->send("after destruction", true));
}

TEST_F(ServerWebSocket, PeerNotAnsweringPingsIsDroppedAfterTheIdleTimeout) {
  ServerOptions options = testOptions();
  options.idle_timeout = std::chrono::seconds(1);
  start(options);
  WsClient client(port());  // a blocking client answers pings only while reading: it never does here
  client.handshake();
  const auto begin = std::chrono::steady_clock::now();
  ASSERT_TRUE(eventually([&] { return recorder(0)->closes() == 1; }, 3000ms));
  EXPECT_GE(std::chrono::steady_clock::now() - begin, 900ms);
  EXPECT_EQ(server_->webSocketConnections(), 0u);
}

TEST_F(ServerWebSocket, RepliesOfSeveralSmallFramesAreNotHeldBack) {
  // Two frames per message: with Nagle on the server's socket the second
  // waits for the client's delayed ACK (40 ms on Linux) every round.
  on_message_ = [](WsConnection& connection, const std::string& data, bool) {
    connection.send(data, false);
    connection.send("ack", false);
  };
  start();
  WsClient client(port());
  client.handshake();
  client.ws.next_layer().set_option(tcp::no_delay(true));  // the client's side is not under test
  constexpr int kRounds = 50;
  const auto begin = std::chrono::steady_clock::now();
  for (int i = 0; i < kRounds; ++i) {
    client.send(std::to_string(i), false);
    ASSERT_EQ(client.read().first, std::to_string(i));
    ASSERT_EQ(client.read().first, "ack");
  }
  const auto per_round = (std::chrono::steady_clock::now() - begin) / kRounds;
  EXPECT_LT(per_round, 10ms) << std::chrono::duration<double, std::milli>(per_round).count() << " ms per round";
}

/// Reads on a thread of its own (answering pings as it goes) until the
/// connection ends.
class BackgroundReader {
 public:
  explicit BackgroundReader(WsClient& client)
      : thread_([this, &client] {
          beast::flat_buffer buffer;
          boost::system::error_code ec;
          while (!ec) {
            client.ws.read(buffer, ec);
            if (ec) break;
            std::lock_guard lock(mutex_);
            messages_.push_back(beast::buffers_to_string(buffer.data()));
            buffer.clear();
          }
          std::lock_guard lock(mutex_);
          error_ = ec;
          ended_ = true;
        }) {}
  ~BackgroundReader() {
    if (thread_.joinable()) thread_.join();
  }

  bool ended() {
    std::lock_guard lock(mutex_);
    return ended_;
  }
  /// Waits for the end; the error that ended the connection.
  boost::system::error_code join() {
    if (thread_.joinable()) thread_.join();
    return error_;
  }
  std::vector<std::string> messages() {
    std::lock_guard lock(mutex_);
    return messages_;
  }

 private:
  std::mutex mutex_;
  std::vector<std::string> messages_;
  boost::system::error_code error_;
  bool ended_ = false;
  std::thread thread_;
};

TEST_F(ServerWebSocket, PausedReadingKeepsAPeerThatAnswersPings) {
  on_message_ = [](WsConnection& connection, const std::string& data, bool) {
    if (data == "pause") connection.pauseReading(true);
  };
  ServerOptions options = testOptions();
  options.idle_timeout = std::chrono::seconds(1);
  start(options);
  WsClient client(port());
  client.handshake();
  client.send("pause", false);
  const auto handler = recorder(0);
  ASSERT_TRUE(eventually([&] { return handler->messages().size() == 1; }));
  BackgroundReader reader(client);  // sends nothing but pongs from here on
  std::this_thread::sleep_for(2500ms);
  EXPECT_FALSE(reader.ended()) << "the server dropped a live peer it had paused";
  EXPECT_EQ(handler->closes(), 0);

  handler->connection()->pauseReading(false);
  EXPECT_TRUE(handler->connection()->send("still here", false));
  ASSERT_TRUE(eventually([&] { return reader.messages() == std::vector<std::string>{"still here"}; }));
  // Beast's own timeout again, the reader answering its pings. Not a multiple of the
  // 0.5 s ping tick: Boost 1.74 runs a timer tick that was already due when a close
  // starts as a close timeout, which resets the socket after the close frame.
  std::this_thread::sleep_for(1250ms);
  EXPECT_FALSE(reader.ended());
  handler->connection()->close(1000, "done");
  EXPECT_EQ(reader.join(), websocket::error::closed);
  EXPECT_EQ(client.ws.reason().code, websocket::close_code::normal);
  EXPECT_EQ(client.ws.reason().reason, "done");
  EXPECT_TRUE(eventually([&] { return handler->closes() == 1; }));
}

TEST_F(ServerWebSocket, PausedReadingStillDropsAPeerThatWentSilent) {
  on_message_ = [](WsConnection& connection, const std::string& data, bool) {
    if (data == "pause") connection.pauseReading(true);
  };
  ServerOptions options = testOptions();
  options.idle_timeout = std::chrono::seconds(1);
  start(options);
  WsClient client(port());  // never reads again, so never answers a ping
  client.handshake();
  client.send("pause", false);
  const auto handler = recorder(0);
  ASSERT_TRUE(eventually([&] { return handler->messages().size() == 1; }));
  const auto begin = std::chrono::steady_clock::now();
  ASSERT_TRUE(eventually([&] { return handler->closes() == 1; }, 3000ms)) << "the handler never learnt of the end";
  EXPECT_GE(std::chrono::steady_clock::now() - begin, 900ms);
  EXPECT_EQ(server_->webSocketConnections(), 0u);
}

TEST_F(ServerWebSocket, StopSendsGoingAway) {
  on_message_ = echo;
  start();
  WsClient client(port());
  client.handshake();
  openedConnection(0);
  BackgroundReader reader(client);
  const auto begin = std::chrono::steady_clock::now();
  server_->stop();
  EXPECT_LT(std::chrono::steady_clock::now() - begin, 500ms);  // the client answered at once
  EXPECT_EQ(reader.join(), websocket::error::closed);
  EXPECT_EQ(client.ws.reason().code, websocket::close_code::going_away);
  EXPECT_EQ(recorder(0)->closes(), 1);
}

TEST_F(ServerWebSocket, StopWaitsForTheCloseAnswerOnlyUpToTheTimeout) {
  accept_.max_send_queue_bytes = 64u << 20;
  ServerOptions options = testOptions();
  options.close_timeout = std::chrono::milliseconds(300);
  start(options);
  WsClient silent(port());  // does not read until the server has stopped
  silent.handshake();
  const auto connection = openedConnection(0);
  // More than the socket buffers hold: the writer is stuck, and the close
  // frame goes in place of what is still queued.
  for (int i = 0; i < 64; ++i) connection->send(std::string(256u << 10, 'q'), true);
  const auto begin = std::chrono::steady_clock::now();
  server_->stop();
  const auto took = std::chrono::steady_clock::now() - begin;
  EXPECT_GE(took, 250ms);
  EXPECT_LT(took, 1500ms);
  EXPECT_EQ(recorder(0)->closes(), 1);
  EXPECT_EQ(connection->queuedBytes(), 0u);
}

TEST_F(ServerWebSocket, CountsWebSocketConnections) {
  start();
  {
    WsClient client(port());
    client.handshake();
    openedConnection(0);
    EXPECT_EQ(server_->webSocketConnections(), 1u);
    EXPECT_EQ(server_->connections(), 1u);
    client.ws.close(websocket::close_code::normal);
  }
  EXPECT_TRUE(eventually([&] { return server_->webSocketConnections() == 0 && server_->connections() == 0; }));
  EXPECT_EQ(recorder(0)->closes(), 1);
}

}  // namespace
}  // namespace rmap::net::test
