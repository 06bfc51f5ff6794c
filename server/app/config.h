#pragma once
/// @file config.h
/// rmapd's configuration: plain structs with defaults, read from a YAML file
/// and overridden by command-line flags (see rmapd_main.cc, docs/API.md).

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "map3d/occupancy_params.h"
#include "slam2d/slam2d.h"

namespace rmap::app {

enum class Role : uint8_t { kRobot, kViewer, kAdmin };
const char* toString(Role role);

struct TokenConfig {
  std::string token;
  Role role = Role::kViewer;
  std::string robot_id;  ///< the only robot a robot token may stream as
};

struct AuthConfig {
  /// With no tokens the server accepts loopback connections only.
  std::vector<TokenConfig> tokens;
  /// Origins allowed on browser WebSockets besides the server's own host.
  std::vector<std::string> allowed_origins;
};

struct LimitsConfig {
  size_t max_frame_bytes = 32u << 20;        ///< robot/viewer WebSocket frames
  size_t max_body_bytes = 64u << 20;         ///< HTTP request bodies
  size_t max_points_per_cloud = 2'000'000;
  /// occupancy:batch; a protobuf request of this many points must fit in max_body_bytes
  size_t max_batch_points = 2'000'000;
  size_t max_in_flight_per_robot = 256;      ///< unacknowledged messages before reading pauses
  double max_messages_per_s_per_robot = 2000;  ///< beyond: Error "rate_limited", message refused
  size_t viewer_send_queue_bytes = 4u << 20; ///< a viewer further behind is skipped
  size_t max_box_cuboids = 100'000;          ///< page size bound of occupancy/box
  /// Blocks of 16³ cells an imported OctoMap may fill (about 150 bytes each once imported);
  /// the file itself is bounded by max_body_bytes
  size_t max_import_blocks = 1'000'000;
  /// Resident memory of rmapd (bytes) above which robot data and imports are refused
  /// with "resource_exhausted" until it falls again; 0 = no bound (see app/memory_bound.h)
  uint64_t max_memory_bytes = 0;
};

struct MapDefaults {
  double resolution_m = 0.1;  ///< for maps created by a Hello without a resolution
  map3d::OccupancyParams occupancy;
  map3d::FusionParams fusion;
  int insert_threads = 1;     ///< threads tracing the rays of one cloud
};

struct Slam2dConfig {
  /// Intensity calibration file (slam2d::IntensityCalibration text) per
  /// scanner model, i.e. the `model` of a Hello's LASER_2D sensor; models
  /// without one are self-calibrated by the SLAM.
  std::map<std::string, std::filesystem::path> calibration_files;
  /// Every map's 2D SLAM; the YAML sets the options a deployment tunes (docs/API.md §2),
  /// the rest keep the defaults fixed across datasets.
  slam2d::Slam2dOptions options;
};

/// Which images place recognition runs on, per map (server/loop's detector with its defaults).
struct LoopClosureConfig {
  bool camera = true;                ///< camera images
  bool cloud_intensity = true;       ///< intensity panoramas of 3D clouds that carry intensities
  bool reflectivity_patches = true;  ///< reflectivity patches of the 2D map around 2D-laser robots
};

/// TLS on the listening port (docs/API.md §2): both files set, or neither
/// (plain TCP). Read at start-up; relative paths from the working directory.
struct TlsConfig {
  std::filesystem::path certificate_file;  ///< PEM: the server's certificate, then any intermediates
  std::filesystem::path private_key_file;  ///< PEM, unencrypted
  bool enabled() const { return !certificate_file.empty() || !private_key_file.empty(); }
};

/// The build's web viewer directory (RMAP_WEB_ROOT, set by CMake; by default
/// the source tree's web/), so a build tree serves the viewer as it is.
std::filesystem::path defaultWebRoot();

struct Config {
  std::string listen_host = "127.0.0.1";
  uint16_t listen_port = 8080;
  std::filesystem::path data_dir = "rmap-data";
  /// The web viewer's files (index.html, app/, node_modules/three), served at /.
  std::filesystem::path web_root = defaultWebRoot();
  int io_threads = 2;
  /// Seconds between map snapshots (recovery replays only the log after them).
  double snapshot_interval_s = 60.0;
  /// Milliseconds between tile-change scans pushed to viewers.
  int viewer_tick_ms = 200;
  AuthConfig auth;
  TlsConfig tls;
  LimitsConfig limits;
  MapDefaults maps;
  Slam2dConfig slam2d;
  LoopClosureConfig loop_closure;
  std::string log_level = "info";
};

/// Reads a YAML config file over `config` (keys absent keep their value).
/// @throws std::runtime_error naming the file and the bad key or value
void loadConfigFile(const std::filesystem::path& file, Config& config);

/// Parses "HOST:PORT" (IPv6 in brackets) into the config.
/// @throws std::invalid_argument for a malformed address
void setListenAddress(const std::string& host_port, Config& config);

/// Bytes of one point in an rmap.v1.OccupancyBatchRequest: three packed doubles.
inline constexpr size_t kBatchBytesPerPoint = 3 * sizeof(double);

/// Bytes of an rmap.v1.OccupancyBatchRequest holding `points` points (the
/// smallest body a batch of that many points can have);
/// `points` <= SIZE_MAX / kBatchBytesPerPoint.
size_t batchRequestBytes(size_t points);

/// @throws std::invalid_argument naming the first bad value
void validate(const Config& config);

}  // namespace rmap::app
