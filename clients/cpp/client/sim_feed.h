#pragma once
/// @file sim_feed.h
/// Simulated robots streaming over the real protocol: each robot follows a
/// planned trajectory through one shared simulated building and sends a 3D
/// lidar cloud (map frame, with intensities) per pose. Used by rmap-sim, by
/// `rmap-bench server` and by the integration tests.

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "sim/building.h"
#include "sim/lidar.h"
#include "sim/voxel_world.h"

namespace rmap::client {

/// Totals so far, for progress reports.
struct SimFeedProgress {
  double elapsed_s = 0.0;
  uint64_t clouds_sent = 0;
  uint64_t clouds_acked = 0;
  uint64_t points_acked = 0;
};

struct SimFeedOptions {
  std::string server_url = "ws://127.0.0.1:8080";
  std::string token;
  int robots = 1;
  /// Map name per robot: "<map_prefix>" shared by all when shared_map, else
  /// "<map_prefix>-<i>".
  std::string map_prefix = "sim";
  bool shared_map = true;
  std::string robot_prefix = "sim-robot";
  double resolution_m = 0.1;
  /// Clouds per second per robot; 0 = as fast as acknowledgements allow.
  double rate_hz = 10.0;
  /// Stop after this long (wall clock) ...
  std::chrono::milliseconds duration{10000};
  /// ... or after this many clouds per robot (0 = no limit).
  uint64_t max_clouds = 0;
  /// Trajectory poses per robot (clouds cycle over them).
  int poses = 200;
  uint64_t seed = 1;
  size_t max_in_flight = 16;
  /// Lidar: beams per ring and rings.
  int lidar_columns = 360;
  int lidar_rings = 16;
  /// Benchmark mode: when > 0 each robot simulates this many distinct clouds
  /// before the clock starts and then cycles over them with fresh stamps, so
  /// a fast feed (rate_hz 0) measures the server rather than the lidar
  /// simulator. 0 = every cloud is simulated at its own pose when sent.
  size_t precompute_clouds = 0;
  /// Per robot: connect, each flow-controlled send, and the final wait for acks.
  std::chrono::milliseconds timeout{10000};
  /// Called about once per second on runSimFeed's thread while robots run; may be empty.
  std::function<void(const SimFeedProgress&)> on_progress;
};

/// Per-robot and total figures of a run.
struct SimFeedResult {
  uint64_t clouds_sent = 0;
  uint64_t clouds_acked = 0;
  uint64_t points_sent = 0;
  std::vector<double> ack_latencies_ms;  ///< every ack
  double wall_s = 0.0;
  std::vector<std::string> errors;       ///< Error replies and connection failures
};

/// The simulated world every robot of a feed drives in (deterministic in `seed`).
struct SimScene {
  sim::VoxelWorld world;
  sim::BuildingLayout layout;
};
SimScene makeSimScene(uint64_t seed, double voxel_m = 0.1);

/// Runs the feed: one thread per robot; returns when every robot stopped and
/// its messages were acknowledged (or failed). Robot failures (connection,
/// Error replies, missing acks) land in SimFeedResult::errors.
/// @throws std::invalid_argument for bad options (robots < 1, rate_hz < 0, bad lidar or poses)
SimFeedResult runSimFeed(const SimScene& scene, const SimFeedOptions& options);

}  // namespace rmap::client
