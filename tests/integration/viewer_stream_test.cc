// What a viewer sees of a robot mapping: change notices and poses on the
// viewer stream, the announced tiles over HTTP with working ETags, and the
// map's cuboids through the paged box query.
#include <gtest/gtest.h>

#include <optional>
#include <set>

#include "api_helpers.h"
#include "client/robot_client.h"
#include "rmapd_process.h"
#include "scene_clouds.h"
#include "viewer_stream.h"

namespace rmap::testing {
namespace {

TEST(ViewerStream, AnnouncesTheTilesAndPosesOfNewCloudsAndTheTilesAnswerWithTheirVersion) {
  TempDir dir("rmap-viewer");
  RmapdProcess rmapd(dir.path() / "data");
  const client::SimScene scene = client::makeSimScene(5);
  const std::vector<v1::RobotMessage> clouds = sceneClouds(scene, 4, 21);

  client::RobotClientOptions options;
  options.server_url = rmapd.wsUrl();
  options.hello.set_robot_id("watched-bot");
  options.hello.set_map("watched");
  client::RobotClient robot(options);
  robot.connect();
  robot.send(clouds[0]);
  ASSERT_TRUE(robot.waitAllAcked(std::chrono::seconds(30)));

  ViewerStream viewer(rmapd.port(), "watched");
  const std::optional<nlohmann::json> hello = viewer.next(std::chrono::seconds(5));
  ASSERT_TRUE(hello);
  EXPECT_EQ((*hello)["type"], "hello");
  EXPECT_EQ((*hello)["map"], "watched");

  client::HttpClient http(rmapd.httpUrl());
  const uint64_t version_before = getJson(http, "/v1/maps/watched")["version"].get<uint64_t>();
  for (size_t i = 1; i < clouds.size(); ++i) robot.send(clouds[i]);
  ASSERT_TRUE(robot.waitAllAcked(std::chrono::seconds(30)));

  // Notices name changed tiles on every level, with versions past the ones
  // before; the robot's latest pose arrives too (frames of one tick in any order).
  std::set<std::vector<int64_t>> announced;  // level, x, y, z, version
  uint64_t announced_version = 0;
  nlohmann::json last_pose;
  while (announced_version < version_before + clouds.size() - 1 || last_pose.is_null() ||
         last_pose["seq"].get<uint64_t>() < clouds.size()) {
    const std::optional<nlohmann::json> frame = viewer.next(std::chrono::seconds(10));
    ASSERT_TRUE(frame) << "no notice of the new clouds; last map_version " << announced_version << ", last pose "
                       << last_pose.dump();
    EXPECT_NE((*frame)["type"], "resync");
    if ((*frame)["type"] == "poses") {
      ASSERT_EQ((*frame)["poses"].size(), 1u);
      last_pose = (*frame)["poses"][0];
      EXPECT_EQ(last_pose["robot_id"], "watched-bot");
    }
    if ((*frame)["type"] != "tiles") continue;
    EXPECT_EQ((*frame)["map"], "watched");
    announced_version = (*frame)["map_version"].get<uint64_t>();
    for (const auto& t : (*frame)["tiles"]) {
      // A tick that lags (loaded machine) may announce the first cloud's tiles after the
      // hello, at their own version; every other tile comes with a version past it.
      if (t[4].get<uint64_t>() > version_before) announced.insert(t.get<std::vector<int64_t>>());
    }
  }
  std::set<int64_t> levels;
  for (const auto& t : announced) levels.insert(t[0]);
  EXPECT_EQ(levels.size(), 7u) << "a changed block changes one tile on every level";
  const v1::Vector3& last = clouds.back().cloud().sensor_pose().position_m();
  EXPECT_NEAR(last_pose["position"][0].get<double>(), last.x(), 1e-9);
  EXPECT_NEAR(last_pose["position"][1].get<double>(), last.y(), 1e-9);
  EXPECT_NEAR(last_pose["position"][2].get<double>(), last.z(), 1e-9);

  // Every announced level-0 tile answers with cuboids and at least the announced version,
  // and its ETag revalidates to 304 while nothing changes.
  size_t tiles_with_cuboids = 0;
  for (const auto& t : announced) {
    if (t[0] != 0) continue;
    const std::string target = "/v1/maps/watched/tiles/0/" + std::to_string(t[1]) + "/" + std::to_string(t[2]) + "/" +
                               std::to_string(t[3]);
    const client::HttpResponse tile = http.get(target, {{"Accept", "application/json"}});
    ASSERT_EQ(tile.status, 200) << target;
    const nlohmann::json body = nlohmann::json::parse(tile.body);
    EXPECT_GE(body["version"].get<int64_t>(), t[4]) << target;
    tiles_with_cuboids += !body["cuboids"].empty();
    const std::string etag = tile.header("etag");
    ASSERT_FALSE(etag.empty());
    const client::HttpResponse again = http.get(target, {{"Accept", "application/json"}, {"If-None-Match", etag}});
    EXPECT_EQ(again.status, 304) << target;
    EXPECT_TRUE(again.body.empty());
    v1::Tile proto;
    ASSERT_TRUE(proto.ParseFromString(http.get(target).body));
    EXPECT_EQ(static_cast<size_t>(proto.probability_size()), body["cuboids"].size());
  }
  EXPECT_GT(tiles_with_cuboids, 0u);

  // The paged box query returns each cuboid of the box once, page after page;
  // cuboids are disjoint and cover exactly the known cells.
  const nlohmann::json info = getJson(http, "/v1/maps/watched");
  const double r = info["resolution_m"].get<double>();
  const auto& lo = info["bounds"]["min"];
  const auto& hi = info["bounds"]["max"];
  const std::string box = "/v1/maps/watched/occupancy/box?min=" + std::to_string(lo[0].get<double>()) + "," +
                          std::to_string(lo[1].get<double>()) + "," + std::to_string(lo[2].get<double>()) +
                          "&max=" + std::to_string(hi[0].get<double>()) + "," + std::to_string(hi[1].get<double>()) +
                          "," + std::to_string(hi[2].get<double>());
  std::set<std::string> seen;
  uint64_t covered_cells = 0;
  size_t pages = 0;
  std::string token;
  do {
    const nlohmann::json page = getJson(http, box + "&limit=5000" + (token.empty() ? "" : "&page_token=" + token));
    for (const auto& c : page["cuboids"]) {
      EXPECT_TRUE(seen.insert(c["min"].dump() + c["max"].dump()).second) << "repeated " << c.dump();
      uint64_t cells = 1;
      for (int a = 0; a < 3; ++a) {
        cells *= static_cast<uint64_t>(std::llround((c["max"][a].get<double>() - c["min"][a].get<double>()) / r));
      }
      covered_cells += cells;
    }
    token = page["next_page_token"].is_null() ? "" : page["next_page_token"].get<std::string>();
    ++pages;
  } while (!token.empty() && pages < 10'000);
  EXPECT_GT(pages, 1u);
  EXPECT_EQ(covered_cells, info["known_cells"].get<uint64_t>());
}

}  // namespace
}  // namespace rmap::testing
