#pragma once
/// @file query_load.h
/// HTTP GET queries issued back to back on several keep-alive connections,
/// cycling over a list of targets, for load tests and benchmarks.

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace rmap::client {

struct QueryLoadOptions {
  std::string server_url = "http://127.0.0.1:8080";
  std::string token;
  int connections = 4;
  /// Paths with queries, e.g. "/v1/maps/lab/occupancy?x=1&y=2&z=0.5"; connection c
  /// starts at target c and takes every one in turn.
  std::vector<std::string> targets;
  std::chrono::milliseconds pause{0};        ///< between two queries of a connection
  std::chrono::milliseconds timeout{10000};  ///< per request
};

struct QueryLoadResult {
  uint64_t answered = 0;
  std::map<int, uint64_t> statuses;   ///< HTTP status → answers
  std::vector<double> latencies_ms;   ///< every answered query
  uint64_t failed = 0;                ///< requests without an answer (connection failures, timeouts)
  std::vector<std::string> first_errors;  ///< why, for the first few of them
  double wall_s = 0.0;
};

class QueryLoad {
 public:
  /// Starts one thread per connection.
  /// @throws std::invalid_argument without targets or connections
  explicit QueryLoad(QueryLoadOptions options);
  ~QueryLoad();  ///< stops
  QueryLoad(const QueryLoad&) = delete;
  QueryLoad& operator=(const QueryLoad&) = delete;

  /// Lets each connection finish its query, joins them and returns the totals. Once only.
  QueryLoadResult stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rmap::client
