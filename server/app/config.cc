#include "app/config.h"

#include <yaml-cpp/yaml.h>

#include "app/slam2d_layer.h"
#include "map3d/cuboid_map.h"

#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>

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

/// One mapping of the file. Each key is named once, where it is read, and a
/// key nobody read is refused when the section closes: a misspelt key would
/// otherwise be ignored and its default used without a word.
class Section {
 public:
  /// @param node  the mapping; absent or empty: a section without keys
  /// @param path  its path in the file ("" for the top level), for messages
  Section(const YAML::Node& node, std::string path)
      : node_(node && !node.IsNull() ? node : YAML::Node(YAML::NodeType::Map)), path_(std::move(path)) {
    if (!node_.IsMap()) throw std::invalid_argument((path_.empty() ? "the file" : path_) + " must be a mapping");
  }

  /// The value of `key`, absent: an undefined node (false).
  YAML::Node child(const char* key) {
    read_.insert(key);
    return node_[key];
  }
  /// The list at `key` (absent or empty: an empty list).
  /// @throws std::invalid_argument when it is not a list
  YAML::Node list(const char* key) {
    const YAML::Node child_node = child(key);
    if (!child_node || child_node.IsNull()) return YAML::Node(YAML::NodeType::Sequence);
    if (!child_node.IsSequence()) throw std::invalid_argument(pathOf(key) + " must be a list");
    return child_node;
  }
  /// The value of `key` as a T.
  /// @throws std::invalid_argument naming the key and its place in the file when it is not one
  template <typename T>
  T as(const char* key, const YAML::Node& value) const {
    try {
      return value.as<T>();
    } catch (const YAML::BadConversion& e) {
      throw std::invalid_argument(pathOf(key) + ": a value of the wrong kind (line " + std::to_string(e.mark.line + 1) +
                                  ", column " + std::to_string(e.mark.column + 1) + ")");
    }
  }
  /// Sets `value` when the key is present, else leaves it.
  template <typename T>
  void read(const char* key, T& value) {
    if (const YAML::Node child_node = child(key)) value = as<T>(key, child_node);
  }
  void read(const char* key, std::filesystem::path& value) {
    if (const YAML::Node child_node = child(key)) value = as<std::string>(key, child_node);
  }
  /// @throws std::invalid_argument when the key is absent
  template <typename T>
  T required(const char* key) {
    const YAML::Node child_node = child(key);
    if (!child_node) throw std::invalid_argument(pathOf(key) + " is required");
    return as<T>(key, child_node);
  }
  /// Reads the mapping at `key` with `fill(Section&)`, then refuses the keys it did not read.
  template <typename Fill>
  void section(const char* key, Fill&& fill);
  std::string pathOf(const char* key) const { return path_.empty() ? key : path_ + "." + key; }

  /// @throws std::invalid_argument naming the first key not read
  void close() const {
    for (const auto& entry : node_) {
      const std::string key = entry.first.as<std::string>();
      if (!read_.contains(key)) throw std::invalid_argument("unknown key '" + pathOf(key.c_str()) + "'");
    }
  }

 private:
  const YAML::Node node_;  // const: a lookup of an absent key must not add it
  std::string path_;
  std::set<std::string, std::less<>> read_;
};

/// Reads one section with `fill(Section&)`, then refuses the keys it did not read.
template <typename Fill>
void readSection(const YAML::Node& node, std::string path, Fill&& fill) {
  Section section(node, std::move(path));
  fill(section);
  section.close();
}

template <typename Fill>
void Section::section(const char* key, Fill&& fill) {
  readSection(child(key), pathOf(key), std::forward<Fill>(fill));
}

void readAuth(Section& auth_section, AuthConfig& auth) {
  // A key that is there replaces the default, even empty ("tokens:": no token).
  if (auth_section.child("tokens")) {
    auth.tokens.clear();
    for (const YAML::Node& t : auth_section.list("tokens")) {
      readSection(t, auth_section.pathOf("tokens") + "[]", [&](Section& s) {
        TokenConfig token;
        token.token = s.required<std::string>("token");
        token.role = parseRole(s.required<std::string>("role"));
        s.read("robot_id", token.robot_id);
        auth.tokens.push_back(std::move(token));
      });
    }
  }
  auth_section.read("allowed_origins", auth.allowed_origins);
}

void readLimits(Section& s, LimitsConfig& limits) {
  s.read("max_frame_bytes", limits.max_frame_bytes);
  s.read("max_body_bytes", limits.max_body_bytes);
  s.read("max_points_per_cloud", limits.max_points_per_cloud);
  s.read("max_batch_points", limits.max_batch_points);
  s.read("max_in_flight_per_robot", limits.max_in_flight_per_robot);
  s.read("max_messages_per_s_per_robot", limits.max_messages_per_s_per_robot);
  s.read("viewer_send_queue_bytes", limits.viewer_send_queue_bytes);
  s.read("max_box_cuboids", limits.max_box_cuboids);
  s.read("max_import_blocks", limits.max_import_blocks);
  s.read("max_memory_bytes", limits.max_memory_bytes);
}

void readMaps(Section& s, MapDefaults& maps) {
  s.read("resolution_m", maps.resolution_m);
  s.read("insert_threads", maps.insert_threads);
  s.read("max_range_m", maps.occupancy.max_range_m);
  s.read("hit_log_odds", maps.occupancy.hit_log_odds);
  s.read("miss_log_odds", maps.occupancy.miss_log_odds);
  s.read("fusion_tolerance_log_odds", maps.fusion.tolerance_log_odds);
}

/// The geometric loop closure of the 2D SLAM: the options a deployment tunes.
void readSlam2dLoopClosure(Section& s, slam2d::LoopClosureOptions& loop) {
  s.read("enabled", loop.enabled);
  s.read("min_score", loop.min_score);
  s.read("sparse_min_score", loop.sparse_min_score);
  s.read("sparse_loop_edge_keyframes", loop.sparse_loop_edge_keyframes);
  s.read("member_check_exclusion_m", loop.member_check_exclusion_m);
  s.read("member_check_near_exclusion_m", loop.member_check_near_exclusion_m);
  s.read("member_check_max_turn_rad", loop.member_check_max_turn_rad);
  s.read("member_check_max_shift_m", loop.member_check_max_shift_m);
  s.read("ambiguity_margin", loop.submap.ambiguity_margin);
  s.read("ambiguous_min_score", loop.ambiguous_min_score);
  s.read("support_min_separation_m", loop.support_min_separation_m);
  s.read("min_match_points", loop.min_match_points);
  s.read("max_window_m", loop.max_window_m);
  s.read("max_window_rad", loop.max_window_rad);
  s.read("confirm_after_s", loop.confirm_after_s);
  s.read("rerender_checkpoints", loop.rerender_checkpoints);
}

void readSlam2d(Section& s, Slam2dConfig& slam2d) {
  std::map<std::string, std::string> files;
  s.read("calibrations", files);
  for (const auto& [model, file] : files) slam2d.calibration_files[model] = file;
  slam2d::Slam2dOptions& o = slam2d.options;
  s.read("resolution_m", o.resolution_m);
  s.read("range_min_m", o.range_min_m);
  s.read("range_max_m", o.range_max_m);
  s.read("use_odometry", o.use_odometry);
  s.read("map_update_distance_m", o.map_update_distance_m);
  s.read("map_update_angle_rad", o.map_update_angle_rad);
  s.read("reflectivity_weight", o.reflectivity_weight);
  s.read("self_calibration", o.self_calibration);
  s.read("relock_after_large_step_m", o.relock_after_large_step_m);
  s.section("loop_closure", [&](Section& loop) { readSlam2dLoopClosure(loop, o.loop_closure); });
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
    readSection(YAML::LoadFile(file.string()), "", [&](Section& root) {
      if (const YAML::Node listen = root.child("listen")) setListenAddress(root.as<std::string>("listen", listen), config);
      root.read("data_dir", config.data_dir);
      root.read("web_root", config.web_root);
      root.read("io_threads", config.io_threads);
      root.read("snapshot_interval_s", config.snapshot_interval_s);
      root.read("viewer_tick_ms", config.viewer_tick_ms);
      root.read("log_level", config.log_level);
      root.section("auth", [&](Section& s) { readAuth(s, config.auth); });
      root.section("tls", [&](Section& s) {
        s.read("certificate_file", config.tls.certificate_file);
        s.read("private_key_file", config.tls.private_key_file);
      });
      root.section("limits", [&](Section& s) { readLimits(s, config.limits); });
      root.section("maps", [&](Section& s) { readMaps(s, config.maps); });
      root.section("loop_closure", [&](Section& s) {
        s.read("camera", config.loop_closure.camera);
        s.read("cloud_intensity", config.loop_closure.cloud_intensity);
        s.read("reflectivity_patches", config.loop_closure.reflectivity_patches);
      });
      root.section("slam2d", [&](Section& s) { readSlam2d(s, config.slam2d); });
    });
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
