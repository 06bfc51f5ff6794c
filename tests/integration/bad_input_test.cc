// Hostile and broken input: every case gets a clear error, changes nothing
// and leaves the server serving.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <netinet/in.h>

#include <cmath>
#include <condition_variable>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <utility>

#include "api_helpers.h"
#include "client/robot_client.h"
#include "rmapd_process.h"
#include "scene_clouds.h"

namespace rmap::testing {
namespace {

// Small limits, so that crossing each one is quick; one extra browser Origin.
const std::string kBadInputConfig = std::string(kRoleTokensYaml) +
                            "  allowed_origins: [\"https://viewer.example\"]\n"
                            "limits:\n  max_frame_bytes: 1048576\n  max_body_bytes: 1048576\n"
                            "  max_batch_points: 1000\n  max_points_per_cloud: 20000\n";

class BadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    rmapd_ = std::make_unique<RmapdProcess>(dir_.path() / "data", kBadInputConfig);
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

  /// A WebSocket upgrade of `path` as a browser sends it (plus `headers`);
  /// the HTTP answer: 101, or the refusal.
  client::HttpResponse upgrade(const std::string& path, std::map<std::string, std::string> headers) {
    headers.insert({{"Connection", "Upgrade"},
                    {"Upgrade", "websocket"},
                    {"Sec-WebSocket-Version", "13"},
                    {"Sec-WebSocket-Key", "dGhlIHNhbXBsZSBub25jZQ=="}});
    client::HttpClient http(rmapd_->httpUrl());
    return http.get(path, headers);
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

/// The code and message of a JSON error body.
using ErrorText = std::pair<std::string, std::string>;

ErrorText errorOf(const client::HttpResponse& response) {
  const nlohmann::json body = nlohmann::json::parse(response.body, nullptr, false);
  if (!body.is_object() || !body.contains("error")) return {"(not a JSON error)", response.body};
  return {body["error"]["code"].get<std::string>(), body["error"]["message"].get<std::string>()};
}

std::string connectError(const std::function<void()>& connect) {
  try {
    connect();
  } catch (const client::ClientError& e) {
    return e.what();
  }
  ADD_FAILURE() << "the connection was accepted";
  return {};
}

TEST_F(BadInput, ARobotTokenCannotStreamAsAnotherRobotNorUseAdminEndpoints) {
  const std::string refused = connectError([&] { connect("robot-token-1", "bot-2"); });
  EXPECT_NE(refused.find("server error permission_denied: this token may only stream as robot 'bot-1'"),
            std::string::npos)
      << refused;
  client::HttpClient admin(rmapd_->httpUrl(), "admin-token-1");
  EXPECT_EQ(errorOf(admin.get("/v1/robots/bot-2")).first, "robot_not_found") << "the refused Hello was recorded";

  client::HttpClient robot(rmapd_->httpUrl(), "robot-token-1");
  const client::HttpResponse metrics = robot.get("/metrics");
  EXPECT_EQ(metrics.status, 403);
  EXPECT_EQ(errorOf(metrics), ErrorText("permission_denied", "metrics need an admin token"));
  const client::HttpResponse import = robot.post("/v1/maps/guarded:import?replace=true", "# Octomap OcTree binary file\n",
                                                 "application/octet-stream");
  EXPECT_EQ(import.status, 403);
  EXPECT_EQ(errorOf(import),
            ErrorText("permission_denied", "importing a map needs an admin token"));
  expectServing();
}

TEST_F(BadInput, AViewerTokenIsReadOnly) {
  const std::string refused = connectError([&] { connect("viewer-token-1"); });
  EXPECT_NE(refused.find("upgrade refused: HTTP 403"), std::string::npos) << refused;
  EXPECT_NE(refused.find("a viewer token cannot stream robot data"), std::string::npos) << refused;
  client::HttpClient viewer(rmapd_->httpUrl(), "viewer-token-1");
  const client::HttpResponse import = viewer.post("/v1/maps/guarded:import?replace=true", "# Octomap OcTree binary file\n",
                                                  "application/octet-stream");
  EXPECT_EQ(import.status, 403);
  EXPECT_EQ(errorOf(import).first, "permission_denied");
  EXPECT_EQ(errorOf(viewer.get("/metrics")).first, "permission_denied");
  // What a viewer may do: read, including batch queries (a POST that changes nothing).
  EXPECT_EQ(batchQuery(viewer, "guarded", {Eigen::Vector3d(0.0, 0.0, 0.0)}).states_size(), 1);
  expectServing();
}

TEST_F(BadInput, StreamsNeedAValidToken) {
  const std::string anonymous = connectError([&] { connect(""); });
  EXPECT_NE(anonymous.find("HTTP 401"), std::string::npos) << anonymous;
  EXPECT_NE(anonymous.find("a bearer token is required"), std::string::npos) << anonymous;
  const client::HttpResponse none = upgrade("/v1/stream/viewer", {});
  EXPECT_EQ(none.status, 401);
  EXPECT_EQ(errorOf(none), ErrorText("unauthenticated", "a bearer token is required"));
  const client::HttpResponse basic = upgrade("/v1/stream/viewer", {{"Authorization", "Basic dmlld2VyOnRva2Vu"}});
  EXPECT_EQ(basic.status, 401);
  EXPECT_EQ(errorOf(basic).second, "Authorization must be 'Bearer <token>'");
  const client::HttpResponse wrong = upgrade("/v1/stream/viewer", {{"Sec-WebSocket-Protocol", "rmap.v1, bearer.guessed-token"}});
  EXPECT_EQ(wrong.status, 401);
  EXPECT_EQ(errorOf(wrong).second, "the token is not valid");
  // A browser's token rides in the subprotocol offer; the answer names rmap.v1 only.
  const client::HttpResponse browser =
      upgrade("/v1/stream/viewer", {{"Sec-WebSocket-Protocol", "rmap.v1, bearer.viewer-token-1"}});
  EXPECT_EQ(browser.status, 101);
  EXPECT_EQ(browser.header("sec-websocket-protocol"), "rmap.v1");
  expectServing();
}

TEST_F(BadInput, AForeignOriginCannotOpenStreams) {
  const std::string own = "http://127.0.0.1:" + std::to_string(rmapd_->port());
  for (const char* path : {"/v1/stream/viewer", "/v1/stream/robot"}) {
    // Even an admin token: a page from another site must not drive the user's credentials.
    const client::HttpResponse foreign =
        upgrade(path, {{"Origin", "https://evil.example"}, {"Authorization", "Bearer admin-token-1"}});
    EXPECT_EQ(foreign.status, 403) << path;
    EXPECT_EQ(errorOf(foreign), ErrorText(
                                    "origin_not_allowed", "this Origin may not open streams on this server"))
        << path;
  }
  // A lookalike of the server's own origin is foreign too.
  EXPECT_EQ(upgrade("/v1/stream/viewer", {{"Origin", own + ".evil.example"}, {"Authorization", "Bearer viewer-token-1"}})
                .status,
            403);
  EXPECT_EQ(upgrade("/v1/stream/viewer", {{"Origin", own}, {"Authorization", "Bearer viewer-token-1"}}).status, 101);
  EXPECT_EQ(upgrade("/v1/stream/viewer",
                    {{"Origin", "https://viewer.example"}, {"Authorization", "Bearer viewer-token-1"}})
                .status,
            101);
  expectServing();
}

TEST_F(BadInput, SizeLimitsHold) {
  client::HttpClient viewer(rmapd_->httpUrl(), "viewer-token-1");
  const client::HttpResponse header = viewer.get("/v1/maps", {{"X-Padding", std::string(17u << 10, 'x')}});
  EXPECT_EQ(header.status, 431);
  EXPECT_EQ(errorOf(header), ErrorText("header_too_large", "request header exceeds 16384 bytes"));

  client::HttpClient body_client(rmapd_->httpUrl(), "viewer-token-1");
  const client::HttpResponse body =
      body_client.post("/v1/maps/guarded/occupancy:batch", std::string((1u << 20) + 1, '\0'), "application/x-protobuf");
  EXPECT_EQ(body.status, 413);
  EXPECT_EQ(errorOf(body),
            ErrorText("payload_too_large", "request body exceeds 1048576 bytes"));

  const client::HttpResponse batch = [&] {
    v1::OccupancyBatchRequest request;
    for (int i = 0; i < 3 * 1001; ++i) request.add_xyz_m(0.0);
    return viewer.post("/v1/maps/guarded/occupancy:batch", request.SerializeAsString(), "application/x-protobuf");
  }();
  EXPECT_EQ(batch.status, 413);
  EXPECT_EQ(errorOf(batch), ErrorText("too_many_points", "at most 1000 points per batch"));

  auto robot = connect("robot-token-1");
  v1::RobotMessage huge = good_;
  huge.set_seq(robot->lastSentSeq() + 1);
  v1::PointCloud& cloud = *huge.mutable_cloud();
  cloud.clear_intensities();
  const int sent_values = cloud.xyz_m_size();  // a multiple of 3: the copies stay whole points
  while (cloud.xyz_m_size() < 3 * 20001) cloud.add_xyz_m(cloud.xyz_m(cloud.xyz_m_size() % sent_values));
  const v1::Error e = expectRefused(*robot, huge.SerializeAsString());
  EXPECT_EQ(e.code(), "invalid_message");
  EXPECT_NE(e.message().find("more than the limit of 20000"), std::string::npos) << e.message();
  EXPECT_EQ(e.seq(), huge.seq());
  expectServing();
}

/// The first IPv4 address of this host that is not loopback, if any.
std::optional<std::string> nonLoopbackAddress() {
  ifaddrs* list = nullptr;
  if (getifaddrs(&list) != 0) return std::nullopt;
  std::optional<std::string> found;
  for (const ifaddrs* a = list; a && !found; a = a->ifa_next) {
    if (!a->ifa_addr || a->ifa_addr->sa_family != AF_INET) continue;
    const in_addr address = reinterpret_cast<const sockaddr_in*>(a->ifa_addr)->sin_addr;
    if ((ntohl(address.s_addr) >> 24) == 127) continue;
    char text[INET_ADDRSTRLEN];
    if (inet_ntop(AF_INET, &address, text, sizeof text)) found = text;
  }
  freeifaddrs(list);
  return found;
}

TEST(LoopbackOnly, WithoutTokensOnlyLoopbackPeersAreServed) {
  const std::optional<std::string> address = nonLoopbackAddress();
  if (!address) GTEST_SKIP() << "this host has no non-loopback IPv4 address to connect from";
  TempDir dir("rmap-loopback");
  RmapdProcess rmapd(dir.path() / "data", {}, std::chrono::seconds(60), {"--listen", "0.0.0.0:0"});
  const std::string remote = *address + ":" + std::to_string(rmapd.port());
  client::HttpClient lan("http://" + remote, "admin-token-1");  // no token is valid in this mode
  const client::HttpResponse maps = lan.get("/v1/maps");
  EXPECT_EQ(maps.status, 403);
  EXPECT_EQ(errorOf(maps), ErrorText(
                               "loopback_only", "no tokens are configured, so only loopback clients are served"));
  EXPECT_EQ(lan.get("/healthz").status, 200);  // unauthenticated everywhere

  client::RobotClientOptions options;
  options.server_url = "ws://" + remote;
  options.hello.set_robot_id("lan-bot");
  options.hello.set_map("lan");
  client::RobotClient robot(options);
  const std::string refused = connectError([&] { robot.connect(); });
  EXPECT_NE(refused.find("HTTP 403"), std::string::npos) << refused;
  EXPECT_NE(refused.find("loopback_only"), std::string::npos) << refused;

  client::HttpClient local(rmapd.httpUrl());
  EXPECT_EQ(getJson(local, "/v1/maps")["maps"].size(), 0u) << "the refused robot created its map";
  EXPECT_EQ(local.get("/metrics").status, 200);  // loopback peers are admin
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
