#pragma once
/// @file api_helpers.h
/// HTTP helpers shared by the end-to-end tests.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "client/http_client.h"
#include "rmap/v1/map_api.pb.h"

namespace rmap::testing {

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

/// Value of an unlabelled metric in Prometheus text, -1 when absent.
inline double metricValue(const std::string& text, const std::string& name) {
  const std::string key = "\n" + name + " ";
  const size_t at = text.find(key);
  return at == std::string::npos ? -1.0 : std::stod(text.substr(at + key.size()));
}

}  // namespace rmap::testing
