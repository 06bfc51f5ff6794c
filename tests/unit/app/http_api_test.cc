#include "app/http_api.h"

#include <gtest/gtest.h>

#include <boost/beast/http/field.hpp>
#include <nlohmann/json.hpp>

#include "app/loop_closures.h"
#include "map3d/octomap_bt.h"
#include "service_test_support.h"

namespace rmap::app {
namespace {

namespace http = boost::beast::http;
using nlohmann::json;
using testing::header;

const net::Peer kApiClient{"127.0.0.1", 40000, true};

/// An API over a service in a fresh data directory, in loopback-only mode (every request is admin).
class HttpApiTest : public ::testing::Test {
 protected:
  net::Response call(http::verb method, const std::string& target,
                     std::initializer_list<std::pair<http::field, std::string>> headers = {}) {
    net::Request request{method, target, 11};
    for (const auto& [field, value] : headers) request.set(field, value);
    return api_.handle(request, kApiClient);
  }
  net::Response get(const std::string& target,
                    std::initializer_list<std::pair<http::field, std::string>> headers = {}) {
    return call(http::verb::get, target, headers);
  }

  store::TempDir dir_;
  MappingService service_{testing::configIn(dir_.path())};
  Authenticator auth_{AuthConfig{}};
  HttpApi api_{service_, auth_};
};

TEST_F(HttpApiTest, MethodNotAllowedNamesTheMethodsOfTheRoute) {
  service_.openMap("lab", 0.0);
  const struct {
    http::verb method;
    std::string target;
    std::string allow;
  } cases[] = {
      {http::verb::post, "/v1/maps", "GET"},
      {http::verb::delete_, "/v1/maps/lab", "GET"},
      {http::verb::get, "/v1/maps/lab/occupancy:batch", "POST"},
      {http::verb::put, "/v1/maps/lab/tiles/0/0/0/0", "GET"},
      {http::verb::post, "/healthz", "GET"},
      {http::verb::post, "/v1/loop-closures", "GET"},
  };
  for (const auto& c : cases) {
    const net::Response response = call(c.method, c.target);
    EXPECT_EQ(response.result_int(), 405) << c.target;
    EXPECT_EQ(header(response, http::field::allow), c.allow) << c.target;
    EXPECT_EQ(json::parse(response.body())["error"]["code"], "method_not_allowed") << c.target;
  }
  EXPECT_EQ(header(get("/v1/maps"), http::field::allow), "");
}

TEST_F(HttpApiTest, InternalErrorsAreGenericAndKeepTheDetailOutOfTheResponse) {
  // A robot row whose sensors do not parse makes the handler throw a non-API exception.
  service_.store().upsertRobot({"bot", "lab", "{secret detail", 1, 1, 0});
  const net::Response response = get("/v1/robots/bot");
  EXPECT_EQ(response.result_int(), 500);
  const json body = json::parse(response.body());
  EXPECT_EQ(body["error"]["code"], "internal_error");
  EXPECT_EQ(body["error"]["message"], "internal server error");
  EXPECT_EQ(response.body().find("secret"), std::string::npos) << response.body();
  EXPECT_EQ(response.body().find("parse"), std::string::npos) << response.body();
}

TEST_F(HttpApiTest, LoopClosuresAreFilteredByMapRobotSourceAndCursor) {
  service_.openMap("lab", 0.0);
  service_.openMap("hall", 0.0);
  store::Store& store = service_.store();
  for (const char* robot : {"r1", "r2", "r3"}) store.upsertRobot({robot, "lab", "[]", 1, 1, 0});
  const auto add = [&](const std::string& map, LoopSource source, const std::string& q, const std::string& m,
                       int64_t stamp) {
    LoopClosure c{map, source, {q, stamp, std::nullopt}, {m, stamp - 5, Eigen::Isometry3d::Identity()}, 0.75,
                  std::nullopt};
    c.query.pose = Eigen::Isometry3d(Eigen::Translation3d(1.0, 2.0, 0.5));
    return *store.appendLoopClosure(toRecord(c, 42));
  };
  const int64_t a = add("lab", LoopSource::kCamera, "r1", "r2", 100);
  const int64_t b = add("lab", LoopSource::kGeometry, "r2", "r2", 200);
  const int64_t c = add("hall", LoopSource::kLaserIntensity, "r3", "r1", 300);
  const auto ids = [&](const std::string& target) {
    std::vector<int64_t> out;
    const net::Response response = get(target);
    EXPECT_EQ(response.result_int(), 200) << target << " " << response.body();
    const json body = json::parse(response.body());
    for (const json& e : body.at("loop_closures")) out.push_back(e.at("id").get<int64_t>());
    return out;
  };
  EXPECT_EQ(ids("/v1/loop-closures"), (std::vector<int64_t>{a, b, c}));
  EXPECT_EQ(ids("/v1/loop-closures?map=lab"), (std::vector<int64_t>{a, b}));
  EXPECT_EQ(ids("/v1/loop-closures?robot=r1"), (std::vector<int64_t>{a, c}));
  EXPECT_EQ(ids("/v1/loop-closures?source=geometry"), (std::vector<int64_t>{b}));
  EXPECT_EQ(ids("/v1/loop-closures?map=lab&robot=r2&since=" + std::to_string(a)), (std::vector<int64_t>{b}));
  EXPECT_EQ(ids("/v1/loop-closures?limit=2"), (std::vector<int64_t>{a, b}));

  const json first = json::parse(get("/v1/loop-closures?limit=1").body()).at("loop_closures").at(0);
  EXPECT_EQ(first.at("map"), "lab");
  EXPECT_EQ(first.at("source"), "camera");
  EXPECT_EQ(first.at("score"), 0.75);
  EXPECT_EQ(first.at("detected_ns"), 42);
  EXPECT_EQ(first.at("query").at("robot_id"), "r1");
  EXPECT_EQ(first.at("query").at("stamp_ns"), 100);
  EXPECT_EQ(first.at("query").at("position"), json::parse("[1.0, 2.0, 0.5]"));
  EXPECT_EQ(first.at("query").at("orientation"), json::parse("[1.0, 0.0, 0.0, 0.0]"));
  EXPECT_EQ(first.at("match").at("robot_id"), "r2");
  EXPECT_EQ(first.at("match").at("stamp_ns"), 95);
  EXPECT_TRUE(first.at("withdrawn_ns").is_null());

  // A closure the 2D pose graph dropped is still listed, with the time it was withdrawn.
  const std::vector<store::LoopClosureRecord> geometry = store.loopClosures({"lab", "", "geometry", 0, 10});
  ASSERT_EQ(geometry.size(), 1u);
  ASSERT_TRUE(store.withdrawLoopClosure(geometry[0], 77));
  const json withdrawn = json::parse(get("/v1/loop-closures?source=geometry").body()).at("loop_closures").at(0);
  EXPECT_EQ(withdrawn.at("id"), b);
  EXPECT_EQ(withdrawn.at("withdrawn_ns"), 77);
}

TEST_F(HttpApiTest, LoopClosureQueriesWithBadParametersAreRefused) {
  service_.openMap("lab", 0.0);
  const struct {
    std::string target;
    int status;
    std::string code;
    std::string says;
  } cases[] = {
      {"/v1/loop-closures?source=lidar", 400, "invalid_argument", "source must be"},
      {"/v1/loop-closures?since=-1", 400, "invalid_argument", "since"},
      {"/v1/loop-closures?since=abc", 400, "invalid_argument", "since"},
      {"/v1/loop-closures?limit=0", 400, "invalid_argument", "limit"},
      {"/v1/loop-closures?limit=100001", 400, "invalid_argument", "limit"},
      {"/v1/loop-closures?robot=bad%20id", 400, "invalid_argument", "robot"},
      {"/v1/loop-closures?robot_id=r1", 400, "invalid_argument", "unknown query parameter 'robot_id'"},
      {"/v1/loop-closures?map=nowhere", 404, "map_not_found", "nowhere"},
      {"/v1/loop-closures?robot=ghost", 404, "robot_not_found", "ghost"},
  };
  for (const auto& c : cases) {
    const net::Response response = get(c.target);
    EXPECT_EQ(response.result_int(), c.status) << c.target;
    const json body = json::parse(response.body());
    EXPECT_EQ(body["error"]["code"], c.code) << c.target;
    EXPECT_NE(body["error"]["message"].get<std::string>().find(c.says), std::string::npos)
        << c.target << ": " << body.dump();
  }
}

TEST_F(HttpApiTest, MetricsReportOpenConnections) {
  service_.setConnectionCounter([] { return size_t{7}; });
  const net::Response response = get("/metrics");
  ASSERT_EQ(response.result_int(), 200);
  EXPECT_NE(("\n" + response.body()).find("\nrmap_http_connections 7\n"), std::string::npos) << response.body();
}

/// A .bt tree of a wall (occupied) in front of free space, 0.1 m cells.
std::string wallBt() {
  std::vector<map3d::BtCell> cells;
  for (int y = -20; y < 20; ++y) {
    for (int z = 0; z < 10; ++z) {
      cells.push_back({{30, y, z}, true});
      for (int x = 0; x < 30; ++x) cells.push_back({{x, y, z}, false});
    }
  }
  return map3d::writeBt(0.1, cells);
}

TEST_F(HttpApiTest, ImportedTreeExportsTheSameTreeAndIsRefusedTwice) {
  const std::string bt = wallBt();
  net::Request request{http::verb::post, "/v1/maps/room:import", 11};
  request.body() = bt;
  net::Response response = api_.handle(request, kApiClient);
  ASSERT_EQ(response.result_int(), 200) << response.body();
  const json answer = json::parse(response.body());
  EXPECT_TRUE(answer["created"].get<bool>());
  EXPECT_EQ(answer["format"], "bt");
  EXPECT_EQ(answer["map"]["known_cells"].get<int>(), 40 * 10 * 31);
  EXPECT_EQ(answer["map"]["occupied_cells"].get<int>(), 40 * 10);
  EXPECT_EQ(json::parse(get("/v1/maps/room/occupancy?x=3.05&y=0&z=0.5").body())["state"], "occupied");
  EXPECT_EQ(json::parse(get("/v1/maps/room/occupancy?x=1&y=0&z=0.5").body())["state"], "free");
  // Out again: the very same tree.
  response = get("/v1/maps/room/export.bt");
  ASSERT_EQ(response.result_int(), 200);
  EXPECT_EQ(header(response, http::field::content_type), "application/octet-stream");
  EXPECT_EQ(response.body(), bt);
  // Not again without replace=true; nothing changed.
  const json before = json::parse(get("/v1/maps/room").body());
  response = api_.handle(request, kApiClient);
  EXPECT_EQ(response.result_int(), 409);
  EXPECT_EQ(json::parse(response.body())["error"]["code"], "map_not_empty");
  EXPECT_EQ(json::parse(get("/v1/maps/room").body())["version"], before["version"]);
  request.target("/v1/maps/room:import?replace=yes");
  EXPECT_EQ(api_.handle(request, kApiClient).result_int(), 400);
  request.target("/v1/maps/room:import?replace=true");
  EXPECT_EQ(api_.handle(request, kApiClient).result_int(), 200);
  // Only POST, a valid name, an OctoMap body.
  response = get("/v1/maps/room:import");
  EXPECT_EQ(response.result_int(), 405);
  EXPECT_EQ(header(response, http::field::allow), "POST");
  request.target("/v1/maps/bad%20name:import");
  EXPECT_EQ(api_.handle(request, kApiClient).result_int(), 400);
  request.target("/v1/maps/other:import");
  request.body() = "not a tree";
  response = api_.handle(request, kApiClient);
  EXPECT_EQ(response.result_int(), 400);
  EXPECT_NE(json::parse(response.body())["error"]["message"].get<std::string>().find("not an OctoMap file"),
            std::string::npos);
  EXPECT_EQ(get("/v1/maps/other").result_int(), 404);
}

TEST(HttpApiImport, AnImportIsBackAfterARestart) {
  store::TempDir dir;
  const std::string bt = wallBt();
  {
    MappingService service(testing::configIn(dir.path()));
    Authenticator auth{AuthConfig{}};
    HttpApi api(service, auth);
    net::Request request{http::verb::post, "/v1/maps/room:import", 11};
    request.body() = bt;
    ASSERT_EQ(api.handle(request, kApiClient).result_int(), 200);
  }
  MappingService service(testing::configIn(dir.path()));
  Authenticator auth{AuthConfig{}};
  HttpApi api(service, auth);
  net::Request request{http::verb::get, "/v1/maps/room/export.bt", 11};
  const net::Response response = api.handle(request, kApiClient);
  ASSERT_EQ(response.result_int(), 200);
  EXPECT_EQ(response.body(), bt);
}

TEST_F(HttpApiTest, WholeLayerImagesNeedALayerAndAKnownName) {
  service_.openMap("lab", 0.0);
  net::Response response = get("/v1/maps/lab/layers/reflectivity.png");
  EXPECT_EQ(response.result_int(), 404);
  EXPECT_EQ(json::parse(response.body())["error"]["code"], "layer_not_found");
  response = get("/v1/maps/lab/layers/heights.png");
  EXPECT_EQ(response.result_int(), 404);
  EXPECT_EQ(json::parse(response.body())["error"]["code"], "not_found");
}

TEST(HttpApiRestart, TileETagsOfAnEarlierStartNeverMatch) {
  store::TempDir dir;
  {
    const std::unique_ptr<store::Store> store = store::Store::open(dir.path());
    store->ensureMap({"lab", 0.1, "{}", 1});
    const v1::RobotMessage cloud = testing::smallCloud(1);
    const store::MessageRecord record{"lab", "bot", 1, v1::RobotMessage::kCloud, 1, cloud.SerializeAsString()};
    store->append({&record, 1});
  }
  const Authenticator auth{AuthConfig{}};
  const auto tile = [&](MappingService& service, const std::string& if_none_match) {
    HttpApi api(service, auth);
    net::Request request{http::verb::get, "/v1/maps/lab/tiles/0/0/0/0", 11};
    request.set(http::field::accept, "application/json");
    if (!if_none_match.empty()) request.set(http::field::if_none_match, if_none_match);
    return api.handle(request, kApiClient);
  };
  std::string before;  // rebuilt from the log, then snapshotted at the stop
  {
    MappingService service(testing::configIn(dir.path()));
    const net::Response response = tile(service, "");
    ASSERT_EQ(response.result_int(), 200);
    EXPECT_EQ(json::parse(response.body())["epoch"], service.epoch());
    before = header(response, http::field::etag);
    EXPECT_EQ(tile(service, before).result_int(), 304);
  }
  MappingService service(testing::configIn(dir.path()));  // loads the snapshot: versions start again
  const net::Response response = tile(service, before);
  EXPECT_EQ(response.result_int(), 200) << "an ETag of the previous start validated a tile";
  const std::string after = header(response, http::field::etag);
  EXPECT_NE(after, before);
  EXPECT_EQ(tile(service, after).result_int(), 304);
  HttpApi api(service, auth);
  net::Request request{http::verb::get, "/v1/maps/lab/tileset.json", 11};
  EXPECT_EQ(json::parse(api.handle(request, kApiClient).body())["epoch"], service.epoch());
}

}  // namespace
}  // namespace rmap::app
