#pragma once
/// @file load_bench.h
/// `rmap-bench load`: a running rmapd under a fleet's load over the network:
/// simulated lidar and 2D-laser robots streaming at a bounded rate, viewers
/// subscribed to every map (some of them stalled, never reading) and HTTP
/// queries, all at once. Reports ack latency percentiles, messages/s, the
/// server's peak resident memory against its bound, viewer frames sent and
/// skipped, and query latency, from the clients and from /metrics.

#include <string>

namespace rmap::bench {

struct LoadBenchOptions {
  std::string server_url = "http://127.0.0.1:8080";  ///< the rmapd under load
  std::string token;           ///< admin (robots, viewers, queries, /metrics); none in loopback-only mode
  int robots = 64;             ///< robots streaming at once, the 2D-laser ones included
  int laser_robots = 8;        ///< of them, 2D-laser robots (the rest carry 3D lidars)
  bool shared_map = false;     ///< all robots on one map (default: one map each)
  double rate_hz = 2.0;        ///< messages per second per robot
  double seconds = 30.0;
  int lidar_rings = 16;
  int lidar_columns = 360;
  int viewers = 32;            ///< viewer streams of every map ...
  int stalled_viewers = 8;     ///< ... of which these never read
  int query_connections = 4;   ///< keep-alive connections querying back to back
  std::string json_out;
};

/// Runs the load once, prints a summary, writes JSON when asked.
/// @return 0, or 1 when a robot saw an error or a message went unacknowledged
int runLoadBench(const LoadBenchOptions& options);

}  // namespace rmap::bench
