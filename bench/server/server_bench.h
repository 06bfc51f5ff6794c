#pragma once
/// @file server_bench.h
/// `rmap-bench server`: rmapd in this process on a loopback port, simulated
/// robots streaming over the real protocol, HTTP clients querying while they
/// do. Reports sustained ingest, ack latency at half of the maximum load,
/// single-point and batch query rates.

#include <string>

namespace rmap::bench {

struct ServerBenchOptions {
  int robots = 16;
  bool shared_map = false;      ///< all robots on one map instead of one map each
  double resolution_m = 0.1;
  double phase_s = 10.0;        ///< length of each timed phase
  int lidar_rings = 16;
  int lidar_columns = 1024;
  size_t precompute_clouds = 8; ///< distinct clouds per robot, cycled
  int query_connections = 4;    ///< keep-alive connections issuing point queries
  int batch_points = 100'000;   ///< points per batch request
  int insert_threads = 1;
  std::string json_out;
};

/// Runs every phase, prints a summary, writes JSON when asked. Returns 0.
int runServerBench(const ServerBenchOptions& options);

}  // namespace rmap::bench
