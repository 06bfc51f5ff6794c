#pragma once
/// @file api_helpers.h
/// HTTP helpers shared by the end-to-end tests, and streaming a list of messages as one robot.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <chrono>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "client/http_client.h"
#include "client/metrics_sampler.h"
#include "client/robot_client.h"
#include "rmap/v1/map_api.pb.h"

namespace rmap::testing {

/// Timeout of test clients whose requests answer a whole map (tens of thousands of cuboids as
/// JSON): a sanitized rmapd on a busy 2-core machine took over 10 s, the client's default.
inline constexpr std::chrono::milliseconds kWholeMapRequestTimeout{60000};

inline nlohmann::json getJson(client::HttpClient& http, const std::string& target, int expected_status = 200) {
  const client::HttpResponse r = http.get(target);
  EXPECT_EQ(r.status, expected_status) << target << ": " << r.body;
  return nlohmann::json::parse(r.body);
}

/// Batch occupancy query through the protobuf endpoint.
inline v1::OccupancyBatchResponse batchQuery(client::HttpClient& http, const std::string& map,
                                             const std::vector<Eigen::Vector3d>& points) {
  v1::OccupancyBatchRequest request;
  for (const Eigen::Vector3d& p : points) {
    for (int a = 0; a < 3; ++a) request.add_xyz_m(p[a]);
  }
  const client::HttpResponse r =
      http.post("/v1/maps/" + map + "/occupancy:batch", request.SerializeAsString(), "application/x-protobuf");
  EXPECT_EQ(r.status, 200) << r.body;
  v1::OccupancyBatchResponse response;
  EXPECT_TRUE(response.ParseFromString(r.body));
  EXPECT_EQ(static_cast<size_t>(response.states_size()), points.size());
  return response;
}

/// Config lines giving rmapd one token per role: robot-token-1 (robot bot-1), viewer-token-1, admin-token-1.
inline constexpr const char* kRoleTokensYaml = R"(
auth:
  tokens:
    - {token: robot-token-1, role: robot, robot_id: bot-1}
    - {token: viewer-token-1, role: viewer}
    - {token: admin-token-1, role: admin}
)";

/// Value of an unlabelled metric in Prometheus text, -1 when absent.
inline double metricValue(const std::string& text, const std::string& name) {
  return client::prometheusValue(text, name);
}

/// Streams messages as one robot and waits for every ack.
inline void streamAll(const std::string& url, const std::string& robot_id, const std::string& map,
            const std::vector<v1::RobotMessage>& messages, const v1::SensorDescription* sensor = nullptr) {
  client::RobotClientOptions options;
  options.server_url = url;
  options.hello.set_robot_id(robot_id);
  options.hello.set_map(map);
  if (sensor) *options.hello.add_sensors() = *sensor;
  client::RobotClient robot(options);
  robot.connect();
  for (const v1::RobotMessage& m : messages) robot.send(m);
  ASSERT_TRUE(robot.waitAllAcked(std::chrono::seconds(60)));
}

/// Waits until the map has fused its blocks after the last message: rmapd fuses a map that
/// received nothing for 1 s (its worker looks every 0.5 s), which changes its cuboids (not their
/// occupancy) and its `cuboids` count. Tests that compare cuboids read at different moments wait
/// for this first: the count must hold over 2.5 s, longer than fusion takes to start.
inline void waitForIdleFusion(client::HttpClient& http, const std::string& map) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  uint64_t before = getJson(http, "/v1/maps/" + map)["cuboids"].get<uint64_t>();
  while (std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2500));
    const uint64_t now = getJson(http, "/v1/maps/" + map)["cuboids"].get<uint64_t>();
    if (now == before) return;
    before = now;
  }
  ADD_FAILURE() << "map " << map << " still changing after 60 s";
}

/// Every cuboid of a map, straight from the box endpoint.
inline std::vector<nlohmann::json> allCuboids(client::HttpClient& http, const std::string& map) {
  const nlohmann::json info = getJson(http, "/v1/maps/" + map);
  std::vector<nlohmann::json> out;
  const auto corner = [&](const char* key) {
    std::ostringstream s;
    s.precision(17);
    s << info["bounds"][key][0].get<double>() << "," << info["bounds"][key][1].get<double>() << ","
      << info["bounds"][key][2].get<double>();
    return s.str();
  };
  std::string token;
  do {
    const nlohmann::json page = getJson(http, "/v1/maps/" + map + "/occupancy/box?min=" + corner("min") +
                                                  "&max=" + corner("max") + "&limit=100000" +
                                                  (token.empty() ? "" : "&page_token=" + token));
    for (const nlohmann::json& c : page["cuboids"]) out.push_back(c);
    token = page["next_page_token"].is_string() ? page["next_page_token"].get<std::string>() : "";
  } while (!token.empty());
  return out;
}

}  // namespace rmap::testing
