// Robot streams that break: half a WebSocket frame and a dropped socket,
// every truncation of a protobuf message, old sequence numbers after a
// reconnect (with other content), and a reconnect while messages of the
// dropped stream are still being committed. Nothing is applied twice and
// nothing half-received is applied at all.
#include <gtest/gtest.h>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <condition_variable>
#include <map>
#include <mutex>
#include <utility>

#include "api_helpers.h"
#include "client/robot_client.h"
#include "column_clouds.h"
#include "rmapd_process.h"

namespace rmap::testing {
namespace {

namespace asio = boost::asio;
namespace websocket = boost::beast::websocket;
using tcp = asio::ip::tcp;

constexpr const char* kBrokenMap = "broken";
constexpr const char* kBrokenStreamConfig = "maps:\n  fusion_tolerance_log_odds: 0\n";

v1::RobotMessage cloudWithSeq(uint64_t index, uint64_t seq) {
  v1::RobotMessage m = columnCloud(index, static_cast<int64_t>(seq));
  m.set_seq(seq);
  return m;
}

/// A client WebSocket frame (binary, FIN, masked as clients must) carrying `payload`.
std::string maskedFrame(const std::string& payload) {
  std::string frame{'\x82'};
  const uint64_t n = payload.size();
  if (n < 126) {
    frame += static_cast<char>(0x80 | n);
  } else if (n < 65536) {
    frame += static_cast<char>(0x80 | 126);
    for (int shift = 8; shift >= 0; shift -= 8) frame += static_cast<char>((n >> shift) & 0xff);
  } else {
    frame += static_cast<char>(0x80 | 127);
    for (int shift = 56; shift >= 0; shift -= 8) frame += static_cast<char>((n >> shift) & 0xff);
  }
  const char mask[4] = {'\x37', '\xfa', '\x21', '\x3d'};
  frame.append(mask, 4);
  for (size_t i = 0; i < n; ++i) frame += static_cast<char>(payload[i] ^ mask[i % 4]);
  return frame;
}

/// Whether each cloud index is in the map once (true) or not at all (false).
void expectClouds(client::HttpClient& http, const std::map<uint64_t, bool>& clouds) {
  std::vector<Eigen::Vector3d> probes;
  std::vector<bool> in;
  for (const auto& [index, expected] : clouds) {
    for (const Eigen::Vector3d& p : columnEndpoints(index)) {
      probes.push_back(p);
      in.push_back(expected);
    }
  }
  const v1::OccupancyBatchResponse served = batchQuery(http, kBrokenMap, probes);
  ASSERT_EQ(static_cast<size_t>(served.states_size()), probes.size());
  for (size_t i = 0; i < probes.size(); ++i) {
    const int i32 = static_cast<int>(i);
    if (in[i]) {
      EXPECT_EQ(served.states(i32), v1::OCCUPIED) << probes[i].transpose();
      EXPECT_NEAR(served.probabilities(i32), oneHitProbability(), 1e-6) << "applied more than once? "
                                                                       << probes[i].transpose();
    } else {
      EXPECT_EQ(served.states(i32), v1::UNKNOWN) << probes[i].transpose();
    }
  }
}

/// Polls the robot's last logged seq until it is `seq` (messages of a dropped
/// stream are committed after the drop).
void waitForLastSeq(client::HttpClient& http, const std::string& robot_id, uint64_t seq) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  uint64_t last = 0;
  while (std::chrono::steady_clock::now() < deadline) {
    const client::HttpResponse r = http.get("/v1/robots/" + robot_id);
    if (r.status == 200) last = nlohmann::json::parse(r.body)["last_seq"].get<uint64_t>();
    if (last >= seq) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(last, seq) << robot_id;
}

class BrokenStream : public ::testing::Test {
 protected:
  /// A client whose acks and errors are kept by seq.
  std::unique_ptr<client::RobotClient> connect(const std::string& robot_id, size_t max_in_flight = 8) {
    client::RobotClientOptions options;
    options.server_url = rmapd_.wsUrl();
    options.hello.set_robot_id(robot_id);
    options.hello.set_map(kBrokenMap);
    options.max_in_flight = max_in_flight;
    auto robot = std::make_unique<client::RobotClient>(options);
    robot->onAck([this](const v1::Ack& ack, std::chrono::nanoseconds) {
      std::lock_guard lock(mutex_);
      acks_.emplace_back(ack);
    });
    robot->onError([this](const v1::Error& e) {
      std::lock_guard lock(mutex_);
      errors_.push_back(e);
      errors_cv_.notify_all();
    });
    robot->connect();
    return robot;
  }

  std::vector<v1::Ack> takeAcks() {
    std::lock_guard lock(mutex_);
    return std::exchange(acks_, {});
  }

  TempDir dir_{"rmap-broken"};
  RmapdProcess rmapd_{dir_.path() / "data", kBrokenStreamConfig};
  client::HttpClient http_{rmapd_.httpUrl()};
  std::mutex mutex_;
  std::condition_variable errors_cv_;
  std::vector<v1::Ack> acks_;
  std::vector<v1::Error> errors_;
};

TEST_F(BrokenStream, HalfAFrameThenADroppedSocketAppliesOnlyTheWholeFrames) {
  constexpr uint64_t kWhole = 12;
  {
    asio::io_context ioc;
    websocket::stream<tcp::socket> ws(ioc);
    ws.next_layer().connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), rmapd_.port()));
    ws.handshake("127.0.0.1:" + std::to_string(rmapd_.port()), "/v1/stream/robot");
    ws.binary(true);
    v1::RobotMessage hello;
    hello.mutable_hello()->set_robot_id("half-bot");
    hello.mutable_hello()->set_map(kBrokenMap);
    ws.write(asio::buffer(hello.SerializeAsString()));
    boost::beast::flat_buffer buffer;
    ws.read(buffer);
    v1::ServerMessage welcome;
    ASSERT_TRUE(welcome.ParseFromString(boost::beast::buffers_to_string(buffer.data())));
    ASSERT_TRUE(welcome.has_welcome());
    for (uint64_t seq = 1; seq <= kWhole; ++seq) {
      ws.write(asio::buffer(cloudWithSeq(seq - 1, seq).SerializeAsString()));
    }
    // Their acks (logged and applied) are read first: a socket closed with unread bytes is reset,
    // and a reset drops what the server had not read yet, unacknowledged (a slow server had not
    // read frames 11 and 12).
    for (uint64_t seq = 1; seq <= kWhole; ++seq) {
      buffer.clear();
      ws.read(buffer);
      v1::ServerMessage reply;
      ASSERT_TRUE(reply.ParseFromString(boost::beast::buffers_to_string(buffer.data())));
      ASSERT_TRUE(reply.has_ack()) << reply.ShortDebugString();
      EXPECT_EQ(reply.ack().seq(), seq);
    }
    // Frame 13: its header and half its payload, then the socket goes.
    const std::string payload = cloudWithSeq(kWhole, kWhole + 1).SerializeAsString();
    const std::string frame = maskedFrame(payload);
    asio::write(ws.next_layer(), asio::buffer(frame.data(), frame.size() - payload.size() / 2));
    ws.next_layer().close();
  }
  waitForLastSeq(http_, "half-bot", kWhole);
  std::map<uint64_t, bool> clouds;
  for (uint64_t i = 0; i < kWhole; ++i) clouds[i] = true;
  clouds[kWhole] = false;
  expectClouds(http_, clouds);
  EXPECT_EQ(getJson(http_, "/healthz")["status"], "ok");

  // The robot reconnects and resends all 13 with their seqs: 12 duplicates, one new.
  auto robot = connect("half-bot");
  for (uint64_t seq = 1; seq <= kWhole + 1; ++seq) robot->resend(cloudWithSeq(seq - 1, seq));
  ASSERT_TRUE(robot->waitAllAcked(std::chrono::seconds(10)));
  std::map<uint64_t, bool> duplicate;
  for (const v1::Ack& ack : takeAcks()) duplicate[ack.seq()] = ack.duplicate();
  ASSERT_EQ(duplicate.size(), kWhole + 1);
  for (uint64_t seq = 1; seq <= kWhole; ++seq) EXPECT_TRUE(duplicate[seq]) << seq;
  EXPECT_FALSE(duplicate[kWhole + 1]);
  clouds[kWhole] = true;
  expectClouds(http_, clouds);
}

TEST_F(BrokenStream, EveryTruncationOfAMessageIsRefusedAndChangesNothing) {
  auto robot = connect("cut-bot");
  const std::string whole = cloudWithSeq(0, 1).SerializeAsString();
  for (size_t length = 0; length < whole.size(); ++length) robot->sendRaw(whole.substr(0, length));
  {
    std::unique_lock lock(mutex_);
    ASSERT_TRUE(errors_cv_.wait_for(lock, std::chrono::seconds(10), [&] { return errors_.size() >= whole.size(); }))
        << errors_.size() << " errors for " << whole.size() << " truncated frames";
    for (const v1::Error& e : errors_) {
      EXPECT_EQ(e.code(), "invalid_message") << e.message();
      EXPECT_FALSE(e.fatal());
    }
  }
  EXPECT_TRUE(takeAcks().empty());
  EXPECT_EQ(robot->send(columnCloud(0, 1)), 1u);  // the first durable message: nothing truncated was stored
  ASSERT_TRUE(robot->waitAllAcked(std::chrono::seconds(10)));
  const std::vector<v1::Ack> acks = takeAcks();
  ASSERT_EQ(acks.size(), 1u);
  EXPECT_FALSE(acks[0].duplicate());
  expectClouds(http_, {{0, true}});
}

TEST_F(BrokenStream, OldSeqsAfterAReconnectAreDuplicatesWhateverTheirContent) {
  {
    auto robot = connect("old-bot");
    for (uint64_t i = 0; i < 5; ++i) robot->send(columnCloud(i, 1));
    ASSERT_TRUE(robot->waitAllAcked(std::chrono::seconds(10)));
  }
  takeAcks();
  auto robot = connect("old-bot");
  // Seqs 2 and 4 again, carrying clouds never sent before.
  robot->resend(cloudWithSeq(50, 2));
  robot->resend(cloudWithSeq(51, 4));
  ASSERT_TRUE(robot->waitAllAcked(std::chrono::seconds(10)));
  const std::vector<v1::Ack> acks = takeAcks();
  ASSERT_EQ(acks.size(), 2u);
  for (const v1::Ack& ack : acks) EXPECT_TRUE(ack.duplicate()) << ack.seq();
  expectClouds(http_, {{0, true}, {1, true}, {2, true}, {3, true}, {4, true}, {50, false}, {51, false}});
  EXPECT_EQ(robot->send(columnCloud(5, 6)), 6u);  // new ones continue after the highest seq
}

TEST_F(BrokenStream, AReconnectWhileTheDroppedStreamCommitsNeverReusesItsSeqs) {
  // The same client object drops its stream with 64 messages in flight and reconnects at once:
  // the server may still be committing them, so Welcome.last_durable_seq can be below 64.
  auto robot = connect("fast-bot", 64);
  for (uint64_t i = 0; i < 64; ++i) robot->send(columnCloud(i, 1));
  robot->close();
  robot->connect();
  for (uint64_t i = 64; i < 80; ++i) EXPECT_GT(robot->send(columnCloud(i, 1)), 64u);
  ASSERT_TRUE(robot->waitAllAcked(std::chrono::seconds(10)));
  for (const v1::Ack& ack : takeAcks()) EXPECT_FALSE(ack.seq() > 64 && ack.duplicate()) << "new message acked as a duplicate";
  waitForLastSeq(http_, "fast-bot", 80);
  std::map<uint64_t, bool> clouds;
  for (uint64_t i = 64; i < 80; ++i) clouds[i] = true;  // the new ones, each applied
  expectClouds(http_, clouds);
}

}  // namespace
}  // namespace rmap::testing
