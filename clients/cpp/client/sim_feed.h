#pragma once
/// @file sim_feed.h
/// Simulated robots streaming over the real protocol, through one shared
/// simulated building: lidar robots follow a planned trajectory and send a 3D
/// lidar cloud (map frame, with intensities) per pose; 2D-laser robots
/// (Laser2dRobot) drive the ground storey and send LaserScan2D messages with
/// intensities and drifting odometry, and the PoseEstimates the server's 2D
/// SLAM returns are scored against the truth. A 2D-laser robot whose Welcome
/// says the server holds N of its messages resumes its tour at step N (same
/// seed and poses: the odometry goes on as if it had never stopped). Used by rmap-sim, by
/// `rmap-bench server` and by the integration tests.

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "sim/building.h"
#include "sim/laser2d.h"
#include "sim/lidar.h"
#include "sim/voxel_world.h"

namespace rmap::client {

/// Totals so far, for progress reports.
struct SimFeedProgress {
  double elapsed_s = 0.0;
  uint64_t clouds_sent = 0;
  uint64_t clouds_acked = 0;
  uint64_t points_acked = 0;
  uint64_t scans_sent = 0;
  uint64_t pose_estimates = 0;     ///< PoseEstimates received for scans
  double pose_error_mean_m = 0.0;  ///< their mean distance to the true base position (0 before the first)
};

struct SimFeedOptions {
  std::string server_url = "ws://127.0.0.1:8080";
  std::string token;
  /// Lidar robots (indices 0 .. robots − 1).
  int robots = 1;
  /// 2D-laser robots (indices robots .. robots + laser2d_robots − 1); robots +
  /// laser2d_robots must be at least 1.
  int laser2d_robots = 0;
  /// Their scanner (sim::Laser2dModel::sickLike() or hokuyoLike(); the model
  /// name goes into the Hello and selects the server's calibration).
  sim::Laser2dModel laser2d_model = sim::Laser2dModel::sickLike();
  /// Map name per robot: "<map_prefix>" shared by all when shared_map, else
  /// "<map_prefix>-<i>".
  std::string map_prefix = "sim";
  bool shared_map = true;
  std::string robot_prefix = "sim-robot";
  double resolution_m = 0.1;
  /// Messages (clouds or scans) per second per robot; 0 = as fast as acknowledgements allow.
  double rate_hz = 10.0;
  /// Stop after this long (wall clock) ...
  std::chrono::milliseconds duration{10000};
  /// ... or after this many messages per robot (0 = no limit).
  uint64_t max_clouds = 0;
  /// Trajectory poses per robot (lidar clouds cycle over them; 2D-laser robots
  /// drive them forwards and back).
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
  /// 2D-laser robots always simulate each scan when sent.
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
  uint64_t scans_sent = 0;
  uint64_t scans_acked = 0;
  /// PoseEstimates for scans and their distance to the true base position (m).
  uint64_t pose_estimates = 0;
  double pose_error_mean_m = 0.0;  ///< 0 without estimates
  double pose_error_max_m = 0.0;
  double heading_error_max_rad = 0.0;
  std::vector<double> ack_latencies_ms;  ///< every ack
  double wall_s = 0.0;
  std::vector<std::string> errors;       ///< Error replies and connection failures
};

/// The simulated world every robot of a feed drives in (deterministic in
/// `seed`): two storeys, the reflective tape markers reaching the 2D lasers' plane.
struct SimScene {
  sim::VoxelWorld world;
  sim::BuildingLayout layout;
};
SimScene makeSimScene(uint64_t seed, double voxel_m = 0.1);

/// Runs the feed: one thread per robot; returns when every robot stopped and
/// its messages were acknowledged (or failed). Robot failures (connection,
/// Error replies, missing acks) land in SimFeedResult::errors.
/// @throws std::invalid_argument for bad options (robots < 0, laser2d_robots < 0, no robot,
///         rate_hz < 0, bad lidar, laser or poses)
SimFeedResult runSimFeed(const SimScene& scene, const SimFeedOptions& options);

}  // namespace rmap::client
