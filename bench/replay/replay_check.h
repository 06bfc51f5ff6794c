#pragma once
/// @file replay_check.h
/// `rmap-bench replay-check`: is the map a server built from a replayed
/// dataset the map the benchmarks build offline from the same file?
///
/// - 3D (`--scans`, as `rmap-bench map3d`): the scans go into a CuboidMap
///   with the library defaults at the given resolution, one insertScan per
///   scan; then every block is fused (fuseAll), as the benchmark does before
///   it counts. The server's /v1/maps/{map} statistics are compared with both
///   the unfused and the fused map (a live server keeps its newest blocks
///   dense and counts each of their known cells as a cuboid; its snapshots
///   store them fused), and a grid of occupancy queries (every `grid_step`-th
///   cell centre of the bounds, plus every known cell up to 500,000) is put
///   to the server's batch endpoint and compared state for state.
/// - 2D (`--log`, as `rmap-bench slam2d --loop-closure on`, the server's
///   SLAM options): the log's scans and odometry go through slam2d::Slam2d;
///   the server's map_server export (grid2d.pgm/.yaml) must equal the one
///   drawn from the offline grid byte for byte, and the server's trajectory
///   is compared pose by pose.

#include <string>

namespace rmap::bench {

struct ReplayCheckOptions {
  std::string server_url;   ///< http://host:port
  std::string token;
  std::string map;
  std::string scans_source; ///< a map3d source (loadBenchDataset), or empty
  double resolution_m = 0.1;
  int grid_step_cells = 4;
  std::string log_path;     ///< a CARMEN log (loadSlam2dDataset), or empty
  std::string robot_id;     ///< the replayed robot (2D trajectory); it must have streamed into this map only
  std::string json_out;
  std::string shared_data_dir;
};

/// @return 0 when the server's map equals the offline one, 1 otherwise
int runReplayCheck(const ReplayCheckOptions& options);

}  // namespace rmap::bench
