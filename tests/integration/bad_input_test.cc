// Hostile and broken input: every case gets a clear error, changes nothing
// and leaves the server serving.
#include <gtest/gtest.h>

#include <cmath>
#include <condition_variable>
#include <deque>
#include <limits>
#include <mutex>

#include "api_helpers.h"
#include "client/robot_client.h"
#include "rmapd_process.h"
#include "scene_clouds.h"

namespace rmap::testing {
namespace {

const std::string kConfig = std::string(kRoleTokensYaml) + "limits:\n  max_frame_bytes: 1048576\n";

class BadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    rmapd_ = std::make_unique<RmapdProcess>(dir_.path() / "data", kConfig);
    // One good cloud so there is a map whose version must not move.
    const client::SimScene scene = client::makeSimScene(2);
    good_ = sceneClouds(scene, 1, 9).front();
    auto robot = connect("robot-token-1");
    robot->send(good_);
    ASSERT_TRUE(robot->waitAllAcked(std::chrono::seconds(30)));
    version_ = mapVersion();
  }

  std::unique_ptr<client::RobotClient> connect(const std::string& token, const std::string& robot_id = "bot-1") {
    client::RobotClientOptions options;
    options.server_url = rmapd_->wsUrl();
    options.token = token;
    options.hello.set_robot_id(robot_id);
    options.hello.set_map("guarded");
    options.timeout = std::chrono::milliseconds(5000);
    auto robot = std::make_unique<client::RobotClient>(options);
    robot->onError([this](const v1::Error& e) {
      std::lock_guard lock(errors_mutex_);
      errors_.push_back(e);
      errors_cv_.notify_all();
    });
    robot->connect();
    return robot;
  }

  uint64_t mapVersion() {
    client::HttpClient http(rmapd_->httpUrl(), "viewer-token-1");
    return getJson(http, "/v1/maps/guarded")["version"].get<uint64_t>();
  }

  /// Sends one message and returns the Error it drew (the map must not change).
  v1::Error expectRefused(client::RobotClient& robot, const std::string& bytes) {
    robot.sendRaw(bytes);
    std::unique_lock lock(errors_mutex_);
    if (!errors_cv_.wait_for(lock, std::chrono::seconds(10), [&] { return !errors_.empty(); })) {
      ADD_FAILURE() << "no Error reply";
      return {};
    }
    const v1::Error e = errors_.front();
    errors_.pop_front();
    return e;
  }

  void expectServing() {
    client::HttpClient http(rmapd_->httpUrl());
    EXPECT_EQ(getJson(http, "/healthz")["status"], "ok");
    EXPECT_EQ(mapVersion(), version_) << "bad input changed the map";
  }

  TempDir dir_{"rmap-bad"};
  std::unique_ptr<RmapdProcess> rmapd_;
  v1::RobotMessage good_;
  uint64_t version_ = 0;
  std::mutex errors_mutex_;
  std::condition_variable errors_cv_;
  std::deque<v1::Error> errors_;
};

TEST_F(BadInput, GarbageFrameGetsInvalidMessage) {
  auto robot = connect("robot-token-1");
  const v1::Error e = expectRefused(*robot, std::string("\xff\xff\xff\xff garbage", 12));
  EXPECT_EQ(e.code(), "invalid_message");
  EXPECT_FALSE(e.fatal());
  expectServing();
}

TEST_F(BadInput, NanPointIsRefusedWithItsIndex) {
  auto robot = connect("robot-token-1");
  v1::RobotMessage bad = good_;
  bad.set_seq(robot->lastSentSeq() + 1);
  bad.mutable_cloud()->set_xyz_m(4, std::numeric_limits<float>::quiet_NaN());
  const v1::Error e = expectRefused(*robot, bad.SerializeAsString());
  EXPECT_EQ(e.code(), "invalid_message");
  EXPECT_NE(e.message().find("point 1"), std::string::npos) << e.message();
  EXPECT_EQ(e.seq(), bad.seq());
  expectServing();
}

TEST_F(BadInput, WrongSizesAndTypesAreRefused) {
  auto robot = connect("robot-token-1");
  v1::RobotMessage ragged = good_;
  ragged.set_seq(robot->lastSentSeq() + 1);
  ragged.mutable_cloud()->add_xyz_m(1.0f);  // not a multiple of 3
  EXPECT_NE(expectRefused(*robot, ragged.SerializeAsString()).message().find("multiple of 3"), std::string::npos);

  v1::RobotMessage hello_again;
  hello_again.set_seq(ragged.seq() + 1);
  hello_again.mutable_hello()->set_robot_id("bot-1");
  hello_again.mutable_hello()->set_map("guarded");
  EXPECT_NE(expectRefused(*robot, hello_again.SerializeAsString()).message().find("hello"), std::string::npos);

  v1::RobotMessage empty;
  empty.set_seq(ragged.seq() + 2);
  EXPECT_NE(expectRefused(*robot, empty.SerializeAsString()).message().find("no body"), std::string::npos);
  expectServing();
}

TEST_F(BadInput, DataBeforeHelloIsFatal) {
  client::RobotClientOptions options;
  options.server_url = rmapd_->wsUrl();
  options.token = "robot-token-1";
  options.hello.set_robot_id("");  // invalid hello: refused, fatal
  options.hello.set_map("guarded");
  client::RobotClient robot(options);
  EXPECT_THROW(robot.connect(), client::ClientError);
  expectServing();
}

TEST_F(BadInput, OversizeFrameClosesTheStream) {
  auto robot = connect("robot-token-1");
  robot->sendRaw(std::string(2u << 20, 'x'));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (robot->connected() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_FALSE(robot->connected());
  expectServing();
}

TEST_F(BadInput, TokensAreChecked) {
  EXPECT_THROW(connect(""), client::ClientError);                 // none
  EXPECT_THROW(connect("not-a-valid-token"), client::ClientError);  // unknown
  try {
    connect("robot-token-1", "bot-2");  // another robot's stream
    ADD_FAILURE() << "a robot token streamed as another robot";
  } catch (const client::ClientError& e) {
    EXPECT_NE(std::string(e.what()).find("bot-1"), std::string::npos) << e.what();
  }
  EXPECT_THROW(connect("viewer-token-1"), client::ClientError);  // read-only

  client::HttpClient anonymous(rmapd_->httpUrl());
  const client::HttpResponse none = anonymous.get("/v1/maps");
  EXPECT_EQ(none.status, 401);
  EXPECT_EQ(nlohmann::json::parse(none.body)["error"]["code"], "unauthenticated");
  client::HttpClient viewer(rmapd_->httpUrl(), "viewer-token-1");
  EXPECT_EQ(viewer.get("/v1/maps").status, 200);
  EXPECT_EQ(viewer.get("/metrics").status, 403);
  client::HttpClient admin(rmapd_->httpUrl(), "admin-token-1");
  EXPECT_EQ(admin.get("/metrics").status, 200);
  expectServing();
}

TEST_F(BadInput, BadHttpParametersGetJsonErrors) {
  client::HttpClient http(rmapd_->httpUrl(), "viewer-token-1");
  const std::vector<std::pair<std::string, int>> cases = {
      {"/v1/maps/nope", 404},
      {"/v1/maps/nope/occupancy?x=0&y=0&z=0", 404},
      {"/v1/maps/guarded/occupancy?x=0&y=0", 400},
      {"/v1/maps/guarded/occupancy?x=abc&y=0&z=0", 400},
      {"/v1/maps/guarded/occupancy?x=nan&y=0&z=0", 400},
      {"/v1/maps/guarded/occupancy/box?min=0,0&max=1,1,1", 400},
      {"/v1/maps/guarded/occupancy/box?min=2,2,2&max=1,1,1", 400},
      {"/v1/maps/guarded/occupancy/box?min=0,0,0&max=1,1,1&limit=0", 400},
      {"/v1/maps/guarded/tiles/99/0/0/0", 400},
      {"/v1/maps/guarded/tiles/0/x/0/0", 400},
      {"/v1/robots/nobody/trajectory", 404},
      {"/v1/nothing", 404},
  };
  for (const auto& [target, status] : cases) {
    const client::HttpResponse r = http.get(target);
    EXPECT_EQ(r.status, status) << target << ": " << r.body;
    const nlohmann::json body = nlohmann::json::parse(r.body, nullptr, false);
    ASSERT_TRUE(body.is_object()) << target;
    EXPECT_TRUE(body["error"]["code"].is_string()) << target;
    EXPECT_FALSE(body["error"]["message"].get<std::string>().empty()) << target;
  }
  const client::HttpResponse bad_json = http.post("/v1/maps/guarded/occupancy:batch", "{\"points\": [[1,2]]}",
                                                  "application/json");
  EXPECT_EQ(bad_json.status, 400);
  const client::HttpResponse bad_proto =
      http.post("/v1/maps/guarded/occupancy:batch", "\xff\xff\xff", "application/x-protobuf");
  EXPECT_EQ(bad_proto.status, 400);
  EXPECT_EQ(http.post("/v1/maps", "{}", "application/json").status, 405);
  expectServing();
}

}  // namespace
}  // namespace rmap::testing
