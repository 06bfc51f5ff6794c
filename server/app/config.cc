#include "app/config.h"

#include <yaml-cpp/yaml.h>

#include "app/slam2d_layer.h"
#include "map3d/cuboid_map.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string_view>

namespace rmap::app {

const char* toString(Role role) {
  switch (role) {
    case Role::kRobot: return "robot";
    case Role::kViewer: return "viewer";
    case Role::kAdmin: return "admin";
  }
  return "?";
}

namespace {

Role parseRole(const std::string& text) {
  if (text == "robot") return Role::kRobot;
  if (text == "viewer") return Role::kViewer;
  if (text == "admin") return Role::kAdmin;
  throw std::invalid_argument("role must be robot, viewer or admin, not '" + text + "'");
}

template <typename T>
void read(const YAML::Node& node, const char* key, T& value) {
  if (const YAML::Node child = node[key]) value = child.as<T>();
}

/// A misspelt key would otherwise be ignored and its default used without a word.
/// @param section  the mapping's path in the file ("" for the top level), for the message
void rejectUnknownKeys(const YAML::Node& node, std::initializer_list<std::string_view> known,
                       const std::string& section) {
  if (!node || node.IsNull()) return;
  if (!node.IsMap()) throw std::invalid_argument((section.empty() ? "the file" : section) + " must be a mapping");
  for (const auto& entry : node) {
    const std::string key = entry.first.as<std::string>();
    if (std::find(known.begin(), known.end(), key) == known.end()) {
      throw std::invalid_argument("unknown key '" + (section.empty() ? key : section + "." + key) + "'");
    }
  }
}

void readAuth(const YAML::Node& node, AuthConfig& auth) {
  if (!node) return;
  rejectUnknownKeys(node, {"tokens", "allowed_origins"}, "auth");
  if (const YAML::Node tokens = node["tokens"]) {
    auth.tokens.clear();
    for (const YAML::Node& t : tokens) {
      rejectUnknownKeys(t, {"token", "role", "robot_id"}, "auth.tokens[]");
      TokenConfig token;
      token.token = t["token"].as<std::string>();
      token.role = parseRole(t["role"].as<std::string>());
      read(t, "robot_id", token.robot_id);
      auth.tokens.push_back(std::move(token));
    }
  }
  if (const YAML::Node origins = node["allowed_origins"]) auth.allowed_origins = origins.as<std::vector<std::string>>();
}

void readLimits(const YAML::Node& node, LimitsConfig& limits) {
  rejectUnknownKeys(node, {"max_frame_bytes", "max_body_bytes", "max_points_per_cloud", "max_batch_points",
                           "max_in_flight_per_robot", "max_messages_per_s_per_robot", "viewer_send_queue_bytes",
                           "max_box_cuboids", "max_import_blocks", "max_memory_bytes"},
                    "limits");
  if (!node) return;
  read(node, "max_frame_bytes", limits.max_frame_bytes);
  read(node, "max_body_bytes", limits.max_body_bytes);
  read(node, "max_points_per_cloud", limits.max_points_per_cloud);
  read(node, "max_batch_points", limits.max_batch_points);
  read(node, "max_in_flight_per_robot", limits.max_in_flight_per_robot);
  read(node, "max_messages_per_s_per_robot", limits.max_messages_per_s_per_robot);
  read(node, "viewer_send_queue_bytes", limits.viewer_send_queue_bytes);
  read(node, "max_box_cuboids", limits.max_box_cuboids);
  read(node, "max_import_blocks", limits.max_import_blocks);
  read(node, "max_memory_bytes", limits.max_memory_bytes);
}

void readMaps(const YAML::Node& node, MapDefaults& maps) {
  rejectUnknownKeys(node, {"resolution_m", "insert_threads", "max_range_m", "hit_log_odds", "miss_log_odds",
                           "fusion_tolerance_log_odds"},
                    "maps");
  if (!node) return;
  read(node, "resolution_m", maps.resolution_m);
  read(node, "insert_threads", maps.insert_threads);
  read(node, "max_range_m", maps.occupancy.max_range_m);
  read(node, "hit_log_odds", maps.occupancy.hit_log_odds);
  read(node, "miss_log_odds", maps.occupancy.miss_log_odds);
  read(node, "fusion_tolerance_log_odds", maps.fusion.tolerance_log_odds);
}

/// The geometric loop closure of the 2D SLAM: the options a deployment tunes.
void readSlam2dLoopClosure(const YAML::Node& node, slam2d::LoopClosureOptions& loop) {
  rejectUnknownKeys(node, {"enabled", "min_score", "sparse_min_score", "max_window_m", "max_window_rad",
                           "confirm_after_s"},
                    "slam2d.loop_closure");
  if (!node) return;
  read(node, "enabled", loop.enabled);
  read(node, "min_score", loop.min_score);
  read(node, "sparse_min_score", loop.sparse_min_score);
  read(node, "max_window_m", loop.max_window_m);
  read(node, "max_window_rad", loop.max_window_rad);
  read(node, "confirm_after_s", loop.confirm_after_s);
}

void readSlam2d(const YAML::Node& node, Slam2dConfig& slam2d) {
  rejectUnknownKeys(node, {"calibrations", "resolution_m", "range_min_m", "range_max_m", "use_odometry",
                           "map_update_distance_m", "map_update_angle_rad", "reflectivity_weight",
                           "self_calibration", "loop_closure"},
                    "slam2d");
  if (!node) return;
  if (const YAML::Node files = node["calibrations"]) {
    for (const auto& [model, file] : files.as<std::map<std::string, std::string>>()) {
      slam2d.calibration_files[model] = file;
    }
  }
  slam2d::Slam2dOptions& o = slam2d.options;
  read(node, "resolution_m", o.resolution_m);
  read(node, "range_min_m", o.range_min_m);
  read(node, "range_max_m", o.range_max_m);
  read(node, "use_odometry", o.use_odometry);
  read(node, "map_update_distance_m", o.map_update_distance_m);
  read(node, "map_update_angle_rad", o.map_update_angle_rad);
  read(node, "reflectivity_weight", o.reflectivity_weight);
  read(node, "self_calibration", o.self_calibration);
  readSlam2dLoopClosure(node["loop_closure"], o.loop_closure);
}

}  // namespace

std::filesystem::path defaultWebRoot() { return RMAP_WEB_ROOT; }

size_t batchRequestBytes(size_t points) {
  const size_t payload = points * kBatchBytesPerPoint;
  size_t length_bytes = 1;  // varint: 7 bits per byte
  for (size_t rest = payload >> 7; rest != 0; rest >>= 7) ++length_bytes;
  return payload == 0 ? 0 : 1 + length_bytes + payload;  // field tag, length, packed doubles
}

void loadConfigFile(const std::filesystem::path& file, Config& config) {
  try {
    const YAML::Node root = YAML::LoadFile(file.string());
    if (root.IsNull()) return;  // an empty file
    rejectUnknownKeys(root, {"listen", "data_dir", "web_root", "io_threads", "snapshot_interval_s", "viewer_tick_ms",
                             "log_level", "auth", "tls", "limits", "maps", "loop_closure", "slam2d"},
                      "");
    if (const YAML::Node listen = root["listen"]) setListenAddress(listen.as<std::string>(), config);
    if (const YAML::Node dir = root["data_dir"]) config.data_dir = dir.as<std::string>();
    if (const YAML::Node dir = root["web_root"]) config.web_root = dir.as<std::string>();
    read(root, "io_threads", config.io_threads);
    read(root, "snapshot_interval_s", config.snapshot_interval_s);
    read(root, "viewer_tick_ms", config.viewer_tick_ms);
    read(root, "log_level", config.log_level);
    readAuth(root["auth"], config.auth);
    if (const YAML::Node tls = root["tls"]) {
      rejectUnknownKeys(tls, {"certificate_file", "private_key_file"}, "tls");
      if (const YAML::Node file = tls["certificate_file"]) config.tls.certificate_file = file.as<std::string>();
      if (const YAML::Node file = tls["private_key_file"]) config.tls.private_key_file = file.as<std::string>();
    }
    readLimits(root["limits"], config.limits);
    readMaps(root["maps"], config.maps);
    if (const YAML::Node loop = root["loop_closure"]) {
      rejectUnknownKeys(loop, {"camera", "cloud_intensity", "reflectivity_patches"}, "loop_closure");
      read(loop, "camera", config.loop_closure.camera);
      read(loop, "cloud_intensity", config.loop_closure.cloud_intensity);
      read(loop, "reflectivity_patches", config.loop_closure.reflectivity_patches);
    }
    readSlam2d(root["slam2d"], config.slam2d);
  } catch (const std::exception& e) {
    throw std::runtime_error("config " + file.string() + ": " + e.what());
  }
}

void setListenAddress(const std::string& host_port, Config& config) {
  const size_t colon = host_port.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == host_port.size()) {
    throw std::invalid_argument("listen address must be HOST:PORT, not '" + host_port + "'");
  }
  std::string host = host_port.substr(0, colon);
  const bool bracketed = host.front() == '[';
  if (bracketed) {
    if (host.size() < 3 || host.back() != ']') {
      throw std::invalid_argument("listen address '" + host_port + "' needs a non-empty [IPv6 address] before ':PORT'");
    }
    host = host.substr(1, host.size() - 2);
  }
  // Unbracketed, "::1:80" could also mean host "::1:80" with the port forgotten.
  if (host.find_first_of("[]") != std::string::npos || (!bracketed && host.find(':') != std::string::npos)) {
    throw std::invalid_argument("listen address '" + host_port + "' is malformed; write IPv6 as [ADDRESS]:PORT");
  }
  const std::string port_text = host_port.substr(colon + 1);
  size_t used = 0;
  int port = -1;
  try {
    port = std::stoi(port_text, &used);
  } catch (const std::exception&) {
  }
  if (used != port_text.size() || port < 0 || port > 65535) {
    throw std::invalid_argument("listen port must be 0..65535, not '" + port_text + "'");
  }
  config.listen_host = host;
  config.listen_port = static_cast<uint16_t>(port);
}

void validate(const Config& config) {
  if (config.io_threads < 1) throw std::invalid_argument("io_threads must be >= 1");
  if (config.web_root.empty()) throw std::invalid_argument("web_root must not be empty");
  static const std::set<std::string> kLogLevels{"trace", "debug", "info", "warn", "error", "critical", "off"};
  if (!kLogLevels.contains(config.log_level)) {
    throw std::invalid_argument("log_level must be one of trace, debug, info, warn, error, critical, off (got \"" +
                                config.log_level + "\")");
  }
  if (!(config.maps.resolution_m > 0.0) || !std::isfinite(config.maps.resolution_m)) {
    throw std::invalid_argument("maps.resolution_m must be finite and > 0");
  }
  if (config.maps.insert_threads < 1) throw std::invalid_argument("maps.insert_threads must be >= 1");
  if (!(config.snapshot_interval_s > 0.0)) throw std::invalid_argument("snapshot_interval_s must be > 0");
  if (config.viewer_tick_ms < 10) throw std::invalid_argument("viewer_tick_ms must be >= 10");
  // Zero would not mean "nothing allowed" everywhere: Beast reads a frame limit of 0 as no limit.
  const LimitsConfig& l = config.limits;
  for (const auto& [name, value] : {std::pair{"max_frame_bytes", l.max_frame_bytes},
                                    {"max_body_bytes", l.max_body_bytes},
                                    {"max_points_per_cloud", l.max_points_per_cloud},
                                    {"max_batch_points", l.max_batch_points},
                                    {"max_in_flight_per_robot", l.max_in_flight_per_robot},
                                    {"viewer_send_queue_bytes", l.viewer_send_queue_bytes},
                                    {"max_box_cuboids", l.max_box_cuboids},
                                    {"max_import_blocks", l.max_import_blocks}}) {
    if (value < 1) throw std::invalid_argument(std::string("limits.") + name + " must be >= 1");
  }
  if (!(config.limits.max_messages_per_s_per_robot > 0.0)) {
    throw std::invalid_argument("limits.max_messages_per_s_per_robot must be > 0");
  }
  // A batch of max_batch_points must be sendable: its compact (protobuf) body has to fit in
  // max_body_bytes, or the advertised point limit is a lie answered with 413 payload_too_large.
  // Refused rather than derived, so neither limit silently differs from what the file says.
  if (config.limits.max_batch_points > SIZE_MAX / kBatchBytesPerPoint ||
      batchRequestBytes(config.limits.max_batch_points) > config.limits.max_body_bytes) {
    throw std::invalid_argument("limits.max_batch_points (" + std::to_string(config.limits.max_batch_points) +
                                ") does not fit in limits.max_body_bytes (" +
                                std::to_string(config.limits.max_body_bytes) + "): a protobuf batch takes " +
                                std::to_string(kBatchBytesPerPoint) + " bytes per point");
  }
  if (config.tls.enabled() && (config.tls.certificate_file.empty() || config.tls.private_key_file.empty())) {
    throw std::invalid_argument("tls needs both certificate_file and private_key_file");
  }
  for (const TokenConfig& t : config.auth.tokens) {
    if (t.token.size() < 8) throw std::invalid_argument("auth tokens must have at least 8 characters");
    if (t.role == Role::kRobot && t.robot_id.empty()) {
      throw std::invalid_argument("a robot token needs its robot_id");
    }
  }
  // The map checks its own parameters; building an empty one is cheap.
  map3d::CuboidMap probe(config.maps.resolution_m, config.maps.occupancy, config.maps.fusion);
  try {
    config.slam2d.options.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("slam2d: ") + e.what());
  }
  loadCalibrations(config.slam2d);
}

}  // namespace rmap::app
