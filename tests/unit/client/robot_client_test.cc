#include "client/robot_client.h"

#include <gtest/gtest.h>

#include <atomic>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <set>
#include <thread>

#include "fake_robot_server.h"

namespace rmap::client {
namespace {

using std::chrono::milliseconds;
using Clock = std::chrono::steady_clock;
using test::FakeRobotServer;
using test::FakeRobotServerOptions;

RobotClientOptions optionsFor(const FakeRobotServer& server, size_t max_in_flight = 8,
                              milliseconds timeout = milliseconds(3000)) {
  RobotClientOptions o;
  o.server_url = server.url();
  o.hello.set_robot_id("bot-1");
  o.hello.set_map("lab");
  o.hello.set_resolution_m(0.05);
  o.max_in_flight = max_in_flight;
  o.timeout = timeout;
  return o;
}

v1::RobotMessage odometry(int64_t stamp_ns) {
  v1::RobotMessage m;
  m.mutable_odometry()->set_stamp_ns(stamp_ns);
  m.mutable_odometry()->mutable_pose()->mutable_position_m()->set_x(0.5 * static_cast<double>(stamp_ns));
  return m;
}

v1::RobotMessage cloud(double x) {
  v1::RobotMessage m;
  v1::PointCloud& c = *m.mutable_cloud();
  c.set_sensor("lidar");
  c.set_stamp_ns(1000);
  c.mutable_sensor_pose()->mutable_position_m()->set_x(x);
  for (float v : {1.0f, 2.0f, 3.0f}) c.add_xyz_m(v);
  return m;
}

double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

TEST(RobotClient, ConnectSendsHelloAndReturnsWelcome) {
  FakeRobotServer server;
  RobotClientOptions o = optionsFor(server);
  o.token = "robot-secret";
  v1::SensorDescription& lidar = *o.hello.add_sensors();
  lidar.set_name("lidar");
  lidar.set_kind(v1::SensorDescription::LIDAR_3D);
  RobotClient robot(o);
  EXPECT_FALSE(robot.connected());
  EXPECT_THROW(robot.send(odometry(0)), ClientError);  // not connected yet
  EXPECT_TRUE(robot.waitAllAcked(milliseconds(0)));  // nothing in flight

  const v1::Welcome welcome = robot.connect();
  EXPECT_TRUE(robot.connected());
  EXPECT_EQ(welcome.robot_id(), "bot-1");
  EXPECT_EQ(welcome.map(), "lab");
  EXPECT_EQ(welcome.session_id(), "fake-session");
  ASSERT_EQ(server.hellos().size(), 1u);
  const v1::Hello hello = server.hellos().front();
  EXPECT_EQ(hello.robot_id(), "bot-1");
  EXPECT_DOUBLE_EQ(hello.resolution_m(), 0.05);
  ASSERT_EQ(hello.sensors_size(), 1);
  EXPECT_EQ(hello.sensors(0).kind(), v1::SensorDescription::LIDAR_3D);
  EXPECT_EQ(server.authorizations(), std::vector<std::string>{"Bearer robot-secret"});
  EXPECT_THROW(robot.connect(), ClientError);  // already connected

  robot.close();
  EXPECT_FALSE(robot.connected());
  EXPECT_THROW(robot.send(odometry(1)), ClientError);
  robot.close();  // idempotent
  // A normal closure: the server got a close frame, not a dropped socket.
  const auto deadline = Clock::now() + milliseconds(2000);
  while (server.cleanCloses() == 0 && Clock::now() < deadline) std::this_thread::sleep_for(milliseconds(5));
  EXPECT_EQ(server.cleanCloses(), 1u);
}

TEST(RobotClient, NoTokenSendsNoAuthorization) {
  FakeRobotServer server;
  RobotClient robot(optionsFor(server));
  robot.connect();
  EXPECT_EQ(server.authorizations(), std::vector<std::string>{""});
}

TEST(RobotClient, SequenceContinuesAfterLastDurableSeq) {
  FakeRobotServerOptions fake;
  fake.last_durable_seq = 41;
  FakeRobotServer server(fake);
  RobotClient robot(optionsFor(server));
  EXPECT_EQ(robot.connect().last_durable_seq(), 41u);
  EXPECT_EQ(robot.send(odometry(1)), 42u);
  EXPECT_EQ(robot.send(odometry(2)), 43u);
  EXPECT_EQ(robot.lastSentSeq(), 43u);
  ASSERT_TRUE(robot.waitAllAcked(milliseconds(3000)));
  EXPECT_EQ(robot.lastAckedSeq(), 43u);
  const auto messages = server.messages();
  ASSERT_EQ(messages.size(), 2u);
  EXPECT_EQ(messages[0].seq(), 42u);
  EXPECT_EQ(messages[0].odometry().stamp_ns(), 1);
  EXPECT_EQ(messages[1].seq(), 43u);
  EXPECT_DOUBLE_EQ(messages[1].odometry().pose().position_m().x(), 1.0);
}

TEST(RobotClient, ReconnectResumesAfterWhatTheServerHolds) {
  FakeRobotServer server;
  RobotClient robot(optionsFor(server));
  robot.connect();
  for (int i = 0; i < 3; ++i) robot.send(odometry(i));
  ASSERT_TRUE(robot.waitAllAcked(milliseconds(3000)));
  robot.close();

  EXPECT_EQ(robot.connect().last_durable_seq(), 3u);
  EXPECT_EQ(robot.send(odometry(9)), 4u);
  ASSERT_TRUE(robot.waitAllAcked(milliseconds(3000)));
  EXPECT_EQ(robot.ackedCount(), 1u);  // per session
  EXPECT_EQ(server.hellos().size(), 2u);
}

TEST(RobotClient, ReconnectNeverReusesTheSeqsOfTheDroppedSession) {
  FakeRobotServerOptions fake;
  fake.ack = false;  // nothing durable yet when the stream drops: Welcome says 0 again
  FakeRobotServer server(fake);
  RobotClient robot(optionsFor(server));
  robot.connect();
  for (int i = 0; i < 3; ++i) robot.send(odometry(i));
  robot.close();
  EXPECT_EQ(robot.connect().last_durable_seq(), 0u);
  EXPECT_EQ(robot.send(odometry(3)), 4u);  // 1..3 may still be committing on the server
}

TEST(RobotClient, ResendKeepsTheOriginalSeqAndNewMessagesNumberAfterTheHighest) {
  FakeRobotServerOptions fake;
  fake.last_durable_seq = 5;
  FakeRobotServer server(fake);
  RobotClient robot(optionsFor(server));
  robot.connect();
  v1::RobotMessage old = odometry(3);
  old.set_seq(3);
  EXPECT_EQ(robot.resend(old), 3u);
  EXPECT_EQ(robot.send(odometry(6)), 6u);  // below the server's last durable seq: numbering is unchanged
  old.set_seq(9);
  EXPECT_EQ(robot.resend(old), 9u);
  EXPECT_EQ(robot.send(odometry(10)), 10u);
  EXPECT_EQ(robot.lastSentSeq(), 10u);
  ASSERT_TRUE(robot.waitAllAcked(milliseconds(3000)));
  EXPECT_EQ(robot.ackedCount(), 4u);
  std::vector<uint64_t> seqs;
  for (const v1::RobotMessage& m : server.messages()) seqs.push_back(m.seq());
  EXPECT_EQ(seqs, (std::vector<uint64_t>{3, 6, 9, 10}));
  EXPECT_EQ(server.messages()[0].odometry().stamp_ns(), 3);
  old.set_seq(0);
  EXPECT_THROW(robot.resend(old), ClientError);
}

TEST(RobotClient, EveryMessageIsAckedWithItsLatency) {
  FakeRobotServerOptions fake;
  fake.ack_delay = milliseconds(5);
  FakeRobotServer server(fake);
  // Callback state outlives the client, whose destructor stops the callbacks.
  std::mutex mutex;
  std::set<uint64_t> acked;
  std::vector<std::chrono::nanoseconds> latencies;
  RobotClient robot(optionsFor(server, 8));
  robot.onAck([&](const v1::Ack& ack, std::chrono::nanoseconds latency) {
    std::lock_guard lock(mutex);
    EXPECT_TRUE(acked.insert(ack.seq()).second) << "seq " << ack.seq() << " acked twice";
    latencies.push_back(latency);
  });
  robot.connect();
  const auto start = Clock::now();
  for (int i = 0; i < 40; ++i) robot.send(cloud(i));
  ASSERT_TRUE(robot.waitAllAcked(milliseconds(5000)));
  const double elapsed_s = secondsSince(start);

  EXPECT_EQ(robot.ackedCount(), 40u);
  EXPECT_EQ(robot.lastAckedSeq(), 40u);
  std::lock_guard lock(mutex);
  ASSERT_EQ(acked.size(), 40u);
  EXPECT_EQ(*acked.begin(), 1u);
  EXPECT_EQ(*acked.rbegin(), 40u);
  for (const auto latency : latencies) {
    EXPECT_GE(latency, milliseconds(5));  // the fake holds each ack that long
    EXPECT_LE(std::chrono::duration<double>(latency).count(), elapsed_s);
  }
  const auto messages = server.messages();
  ASSERT_EQ(messages.size(), 40u);
  EXPECT_DOUBLE_EQ(messages[39].cloud().sensor_pose().position_m().x(), 39.0);
}

TEST(RobotClient, MaxInFlightBoundsUnacknowledgedMessages) {
  FakeRobotServerOptions fake;
  fake.ack_delay = milliseconds(30);
  FakeRobotServer server(fake);
  RobotClient robot(optionsFor(server, 4));
  robot.connect();
  for (int i = 0; i < 16; ++i) robot.send(odometry(i));
  ASSERT_TRUE(robot.waitAllAcked(milliseconds(5000)));
  EXPECT_EQ(server.messages().size(), 16u);
  // The server saw the window fill (acks are late) but never overflow.
  EXPECT_EQ(server.maxOutstanding(), 4u);
}

TEST(RobotClient, RefusedUpgradeReportsStatusAndBody) {
  FakeRobotServerOptions fake;
  fake.refuse_upgrade = true;
  FakeRobotServer server(fake);
  RobotClient robot(optionsFor(server));
  try {
    robot.connect();
    FAIL() << "connected";
  } catch (const ClientError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("401"), std::string::npos) << what;
    EXPECT_NE(what.find(FakeRobotServer::kRefusal), std::string::npos) << what;
  }
  EXPECT_FALSE(robot.connected());
}

TEST(RobotClient, BearerTokenIsChecked) {
  FakeRobotServerOptions fake;
  fake.required_token = "right";
  FakeRobotServer server(fake);
  RobotClientOptions o = optionsFor(server);
  o.token = "wrong";
  RobotClient wrong(o);
  EXPECT_THROW(wrong.connect(), ClientError);
  o.token = "right";
  RobotClient right(o);
  EXPECT_EQ(right.connect().robot_id(), "bot-1");
}

TEST(RobotClient, ErrorReplyAnswersItsSeqAndReachesTheCallback) {
  FakeRobotServerOptions fake;
  fake.error_seq = 2;
  FakeRobotServer server(fake);
  std::mutex mutex;
  std::vector<v1::Error> errors;
  RobotClient robot(optionsFor(server));
  robot.onError([&](const v1::Error& e) {
    std::lock_guard lock(mutex);
    errors.push_back(e);
  });
  robot.connect();
  EXPECT_FALSE(robot.lastError());
  for (int i = 0; i < 3; ++i) robot.send(odometry(i));
  // The refused message counts as answered: nothing stays in flight.
  ASSERT_TRUE(robot.waitAllAcked(milliseconds(3000)));
  EXPECT_EQ(robot.ackedCount(), 2u);
  EXPECT_TRUE(robot.connected());
  ASSERT_TRUE(robot.lastError());
  EXPECT_EQ(robot.lastError()->seq(), 2u);
  EXPECT_EQ(robot.lastError()->code(), "invalid_message");
  std::lock_guard lock(mutex);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0].message(), "refused by the fake");
  EXPECT_FALSE(errors[0].fatal());
}

TEST(RobotClient, FatalErrorClosesAndWaitsFailFast) {
  FakeRobotServerOptions fake;
  fake.ack = false;
  fake.error_seq = 3;
  fake.error_fatal = true;
  FakeRobotServer server(fake);
  RobotClient robot(optionsFor(server, 8, milliseconds(5000)));
  robot.connect();
  for (int i = 0; i < 3; ++i) robot.send(odometry(i));
  const auto start = Clock::now();
  EXPECT_FALSE(robot.waitAllAcked(milliseconds(5000)));  // 1 and 2 never acked; the session ended
  EXPECT_LT(secondsSince(start), 2.0);
  EXPECT_FALSE(robot.connected());
  ASSERT_TRUE(robot.lastError());
  EXPECT_TRUE(robot.lastError()->fatal());
  try {
    robot.send(odometry(4));
    FAIL() << "sent on a closed session";
  } catch (const ClientError& e) {
    EXPECT_NE(std::string(e.what()).find("refused by the fake"), std::string::npos) << e.what();
  }
}

TEST(RobotClient, WaitAllAckedAndSendTimeOutWhenNothingIsAcked) {
  FakeRobotServerOptions fake;
  fake.ack = false;
  FakeRobotServer server(fake);
  RobotClient robot(optionsFor(server, 2, milliseconds(300)));
  robot.connect();
  robot.send(odometry(1));
  robot.send(odometry(2));
  auto start = Clock::now();
  EXPECT_FALSE(robot.waitAllAcked(milliseconds(200)));
  EXPECT_GE(secondsSince(start), 0.19);
  EXPECT_LT(secondsSince(start), 2.0);
  EXPECT_TRUE(robot.connected());

  start = Clock::now();
  try {
    robot.send(odometry(3));  // the window of 2 is full
    FAIL() << "send did not block";
  } catch (const ClientError& e) {
    EXPECT_NE(std::string(e.what()).find("timed out"), std::string::npos) << e.what();
  }
  EXPECT_GE(secondsSince(start), 0.29);
  EXPECT_EQ(robot.lastSentSeq(), 2u);
  EXPECT_EQ(robot.ackedCount(), 0u);
}

TEST(RobotClient, ConnectTimesOutWithoutWelcome) {
  FakeRobotServerOptions fake;
  fake.welcome = false;
  FakeRobotServer server(fake);
  RobotClient robot(optionsFor(server, 8, milliseconds(300)));
  const auto start = Clock::now();
  try {
    robot.connect();
    FAIL() << "connected";
  } catch (const ClientError& e) {
    EXPECT_NE(std::string(e.what()).find("Welcome"), std::string::npos) << e.what();
  }
  EXPECT_LT(secondsSince(start), 2.0);
}

TEST(RobotClient, ConnectionRefusedThrows) {
  uint16_t port = 0;
  {  // a port nobody listens on any more
    boost::asio::io_context ioc;
    boost::asio::ip::tcp::acceptor acceptor(ioc, {boost::asio::ip::make_address("127.0.0.1"), 0});
    port = acceptor.local_endpoint().port();
  }
  RobotClientOptions o;
  o.server_url = "ws://127.0.0.1:" + std::to_string(port);
  o.timeout = milliseconds(2000);
  RobotClient robot(o);
  EXPECT_THROW(robot.connect(), ClientError);
  EXPECT_FALSE(robot.connected());
}

TEST(RobotClient, VanishedServerEndsWaitsAndCloseDoesNotHang) {
  FakeRobotServerOptions fake;
  fake.ack = false;
  auto server = std::make_unique<FakeRobotServer>(fake);
  RobotClient robot(optionsFor(*server, 8, milliseconds(5000)));
  robot.connect();
  robot.send(odometry(1));
  server.reset();  // every socket closes

  const auto start = Clock::now();
  EXPECT_FALSE(robot.waitAllAcked(milliseconds(5000)));
  EXPECT_FALSE(robot.connected());
  EXPECT_THROW(robot.send(odometry(2)), ClientError);
  robot.close();
  EXPECT_LT(secondsSince(start), 2.0);
}

TEST(RobotClient, PoseEstimatesReachTheCallback) {
  FakeRobotServerOptions fake;
  fake.poses = true;
  FakeRobotServer server(fake);
  std::mutex mutex;
  std::vector<v1::PoseEstimate> poses;
  RobotClient robot(optionsFor(server));
  robot.onPose([&](const v1::PoseEstimate& pose) {
    std::lock_guard lock(mutex);
    poses.push_back(pose);
  });
  robot.connect();
  robot.send(cloud(2.5));
  ASSERT_TRUE(robot.waitAllAcked(milliseconds(3000)));  // the pose precedes its ack
  std::lock_guard lock(mutex);
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_EQ(poses[0].seq(), 1u);
  EXPECT_DOUBLE_EQ(poses[0].pose().position_m().x(), 2.5);
}

TEST(RobotClient, SendRawDeliversBytesAsIs) {
  FakeRobotServer server;
  std::atomic<int> errors{0};
  RobotClient robot(optionsFor(server));
  robot.onError([&](const v1::Error& e) {
    EXPECT_EQ(e.code(), "invalid_message");
    ++errors;
  });
  robot.connect();
  robot.sendRaw(std::string("\xff\xff\xff", 3));
  robot.send(odometry(1));  // frames keep their order, so this ack comes after the Error
  ASSERT_TRUE(robot.waitAllAcked(milliseconds(3000)));
  EXPECT_EQ(errors.load(), 1);
  EXPECT_EQ(server.unparsableFrames(), 1u);
  EXPECT_EQ(robot.lastSentSeq(), 1u);  // raw frames take no sequence number
}

}  // namespace
}  // namespace rmap::client
