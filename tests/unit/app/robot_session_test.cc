#include "app/robot_session.h"

#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <thread>

#include "service_test_support.h"

namespace rmap::app {
namespace {

using testing::RecordingConnection;

class RobotSessionTest : public ::testing::Test {
 protected:
  /// Opens a session of robot "bot" on map "lab" and checks its Welcome.
  void SetUp() override {
    session_ = std::make_shared<RobotSession>(service_, Principal{Role::kAdmin, {}});
    session_->onOpen(connection_);
    v1::RobotMessage hello;
    hello.mutable_hello()->set_robot_id("bot");
    hello.mutable_hello()->set_map("lab");
    session_->onMessage(hello.SerializeAsString(), true);
    const std::vector<v1::ServerMessage> sent = connection_->sent();
    ASSERT_EQ(sent.size(), 1u);
    ASSERT_TRUE(sent[0].has_welcome());
  }
  void TearDown() override { session_->onClose(); }

  void send(const v1::RobotMessage& message) { session_->onMessage(message.SerializeAsString(), true); }

  store::TempDir dir_;
  MappingService service_{testing::configIn(dir_.path())};
  std::shared_ptr<RecordingConnection> connection_ = std::make_shared<RecordingConnection>();
  std::shared_ptr<RobotSession> session_;
};

TEST_F(RobotSessionTest, DuplicateIsAckedOnlyAfterTheFirstCopyIsApplied) {
  // Hold the map's worker so the first copy is durable but not yet in the map.
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  service_.findMap("lab")->post(0, std::make_shared<v1::RobotMessage>(), "test", [released] { released.wait(); });

  send(testing::smallCloud(1));
  send(testing::smallCloud(1));  // a resend, e.g. after a reconnect
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (service_.metrics().messages_durable.load() < 1 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ(service_.metrics().messages_durable.load(), 1u);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the duplicate's commit is done by now
  EXPECT_EQ(connection_->sent().size(), 1u) << "an ack went out before the message was in the map";
  EXPECT_EQ(service_.findMap("lab")->map().stats().scans, 0u);

  release.set_value();
  const std::vector<v1::ServerMessage> sent = connection_->waitFor(3);
  ASSERT_EQ(sent.size(), 3u);
  ASSERT_TRUE(sent[1].has_ack());
  EXPECT_EQ(sent[1].ack().seq(), 1u);
  EXPECT_FALSE(sent[1].ack().duplicate());
  ASSERT_TRUE(sent[2].has_ack());
  EXPECT_EQ(sent[2].ack().seq(), 1u);
  EXPECT_TRUE(sent[2].ack().duplicate());
  EXPECT_EQ(service_.findMap("lab")->map().stats().scans, 1u);
}

TEST_F(RobotSessionTest, DuplicateOfAnAppliedMessageIsAckedAtOnce) {
  send(testing::smallCloud(1));
  ASSERT_EQ(connection_->waitFor(2).size(), 2u);
  send(testing::smallCloud(1));
  const std::vector<v1::ServerMessage> sent = connection_->waitFor(3);
  ASSERT_EQ(sent.size(), 3u);
  EXPECT_TRUE(sent[2].ack().duplicate());
}

TEST_F(RobotSessionTest, LastSeenFollowsAcceptedMessagesAndIsStoredAtDisconnect) {
  const int64_t hello_ns = service_.robot("bot")->record.last_seen_ns;
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  send(testing::smallCloud(1));
  ASSERT_EQ(connection_->waitFor(2).size(), 2u);
  const int64_t seen_ns = service_.robot("bot")->record.last_seen_ns;
  EXPECT_GT(seen_ns, hello_ns);
  EXPECT_EQ(seen_ns, session_->lastSeenNs());
  ASSERT_EQ(service_.robots().size(), 1u);
  EXPECT_EQ(service_.robots()[0].record.last_seen_ns, seen_ns);

  session_->onClose();
  EXPECT_FALSE(service_.robot("bot")->connected);
  EXPECT_EQ(service_.store().robot("bot")->last_seen_ns, seen_ns);
}

TEST_F(RobotSessionTest, PersistLastSeenWritesOnlyWhatChanged) {
  send(testing::smallCloud(1));
  ASSERT_EQ(connection_->waitFor(2).size(), 2u);
  service_.persistLastSeen();
  EXPECT_EQ(service_.store().robot("bot")->last_seen_ns, session_->lastSeenNs());
}

TEST_F(RobotSessionTest, CloudFromOutsideTheMapIsRefusedBeforeItIsStored) {
  // 0.1 m cells end at ±3276.8 m.
  send(testing::cloudMessage(1, {5000.0, 0.0, 0.0}, {{4999.0f, 0.0f, 0.0f}}));
  const std::vector<v1::ServerMessage> sent = connection_->waitFor(2);
  ASSERT_EQ(sent.size(), 2u);
  ASSERT_TRUE(sent[1].has_error());
  EXPECT_EQ(sent[1].error().code(), "invalid_message");
  EXPECT_EQ(sent[1].error().seq(), 1u);
  EXPECT_NE(sent[1].error().message().find("addressable range"), std::string::npos) << sent[1].error().message();
  EXPECT_EQ(service_.store().messageCount(), 0u);
  EXPECT_EQ(service_.store().lastSeq("bot"), 0u);
}

TEST_F(RobotSessionTest, SeqAbove2To63IsRefusedAndOthersInItsBatchAreStored) {
  v1::RobotMessage huge = testing::smallCloud(uint64_t{1} << 63);
  send(huge);
  send(testing::smallCloud(1));
  const std::vector<v1::ServerMessage> sent = connection_->waitFor(3);
  ASSERT_EQ(sent.size(), 3u);
  ASSERT_TRUE(sent[1].has_error());
  EXPECT_EQ(sent[1].error().code(), "invalid_message");
  EXPECT_EQ(sent[1].error().seq(), huge.seq());
  ASSERT_TRUE(sent[2].has_ack());
  EXPECT_EQ(sent[2].ack().seq(), 1u);
  EXPECT_EQ(service_.store().messageCount(), 1u);
}

TEST(RobotSessionMemoryBound, AboveTheBoundDataIsRefusedUnstoredAndTheSessionStaysOpen) {
  store::TempDir dir;
  Config config = testing::configIn(dir.path());
  config.limits.max_memory_bytes = 1;  // any process is above one byte
  MappingService service(config);
  auto connection = std::make_shared<RecordingConnection>();
  auto session = std::make_shared<RobotSession>(service, Principal{Role::kAdmin, {}});
  session->onOpen(connection);
  v1::RobotMessage hello;
  hello.mutable_hello()->set_robot_id("bot");
  hello.mutable_hello()->set_map("lab");
  session->onMessage(hello.SerializeAsString(), true);
  session->onMessage(testing::smallCloud(1).SerializeAsString(), true);
  session->onMessage(testing::smallCloud(2).SerializeAsString(), true);

  const std::vector<v1::ServerMessage> sent = connection->waitFor(3);
  ASSERT_EQ(sent.size(), 3u);
  EXPECT_TRUE(sent[0].has_welcome()) << "a robot may still connect and learn its last durable seq";
  for (uint64_t seq : {1u, 2u}) {
    const v1::ServerMessage& reply = sent[seq];
    ASSERT_TRUE(reply.has_error());
    EXPECT_EQ(reply.error().code(), "resource_exhausted");
    EXPECT_EQ(reply.error().seq(), seq);
    EXPECT_FALSE(reply.error().fatal());
    EXPECT_EQ(reply.error().message(),
              "the server is above its memory bound of 9.537e-07 MiB; the message was not acknowledged, resend it later");
  }
  EXPECT_EQ(service.metrics().messages_refused_memory.load(), 2u);
  EXPECT_EQ(service.metrics().messages_rejected.load(), 2u);
  EXPECT_EQ(service.store().messageCount(), 0u);
  EXPECT_EQ(service.findMap("lab")->map().stats().scans, 0u);
  session->onClose();
}

// The first frame of a stream goes through decodeRobotFrame as a Hello: anything else ends the
// stream before a robot or a map is recorded.
TEST(RobotSessionFirstFrame, MustBeAValidHello) {
  store::TempDir dir;
  MappingService service{testing::configIn(dir.path())};
  const auto first = [&](const v1::RobotMessage& message) {
    auto connection = std::make_shared<testing::RecordingConnection>();
    auto session = std::make_shared<RobotSession>(service, Principal{Role::kAdmin, {}});
    session->onOpen(connection);
    session->onMessage(message.SerializeAsString(), true);
    session->onClose();
    const std::vector<v1::ServerMessage> sent = connection->sent();
    return sent.size() == 1 && sent[0].has_error() ? sent[0].error() : v1::Error{};
  };
  const v1::Error cloud = first(testing::smallCloud(4));
  EXPECT_EQ(cloud.code(), "hello_required");
  EXPECT_EQ(cloud.seq(), 4u);
  EXPECT_TRUE(cloud.fatal());
  v1::RobotMessage hello;
  hello.mutable_hello()->set_robot_id("bot");
  hello.mutable_hello()->set_map("../lab");
  const v1::Error bad_map = first(hello);
  EXPECT_EQ(bad_map.code(), "invalid_hello");
  EXPECT_TRUE(bad_map.fatal());
  EXPECT_TRUE(service.robots().empty());
  EXPECT_TRUE(service.maps().empty());
  EXPECT_EQ(service.metrics().messages_rejected.load(), 2u);
}

}  // namespace
}  // namespace rmap::app
