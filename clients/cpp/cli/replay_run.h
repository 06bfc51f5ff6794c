#pragma once
/// @file replay_run.h
/// Streams a ReplaySource to rmapd as one robot (client::RobotClient) and
/// counts what happened: the engine of `rmap replay`.

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/replay_progress.h"
#include "cli/replay_source.h"

namespace rmap::cli {

enum class ReplayRate {
  kRealtime,  ///< frame k leaves (stamp_k − stamp_0) after the first
  kMax,       ///< as fast as acknowledgements allow (the client's in-flight window)
};

struct ReplayOptions {
  std::string server_url;      ///< ws://host:port or wss://host:port
  std::string token;           ///< Bearer token, or empty
  std::string ca_file;         ///< wss://: PEM CA certificates to verify the server against (see RobotClientOptions)
  std::string map;
  std::string robot_id;
  double resolution_m = 0.0;   ///< for a new map; 0: the server's default
  ReplayRate rate = ReplayRate::kMax;
  size_t max_in_flight = 64;   ///< unacknowledged messages at most
  /// Messages per second at most, whatever the rate: rmapd refuses a robot's messages beyond
  /// its limits.max_messages_per_s_per_robot (2000/s by default) as rate_limited.
  double max_messages_per_s = 1000.0;
  std::chrono::milliseconds timeout{60000};  ///< connect, and each wait for acks
};

struct ReplaySummary {
  std::string server, map, robot_id, format;
  size_t frames = 0;      ///< messages the source holds
  size_t sent = 0;
  size_t acked = 0;       ///< acknowledged (durable and in the map)
  size_t duplicates = 0;  ///< of those, acknowledged as already stored
  size_t errors = 0;      ///< refused by the server
  uint64_t points = 0;    ///< cloud points sent
  uint64_t beams = 0;     ///< 2D laser returns sent
  size_t clouds = 0, scans = 0, images = 0;  ///< messages sent by kind
  uint64_t dropped_points = 0;  ///< non-finite points left out
  uint64_t resumed_after_seq = 0;  ///< the robot's last durable seq before this replay (0: a new robot)
  double duration_s = 0.0;
  std::string failure;                  ///< why the replay stopped early; empty when every frame was sent
  std::vector<std::string> error_messages;  ///< the server's first errors ("code: message (seq n)")
  std::vector<std::string> notes;       ///< from the source

  /// Every frame sent and acknowledged, no error.
  bool ok() const { return failure.empty() && errors == 0 && sent == frames && acked == frames; }
  nlohmann::json toJson() const;
  std::string text() const;
};

/// Connects, sends every frame and waits for their acks. Never throws for
/// what the server or the files do: the summary says what failed.
/// @param progress  drawn while streaming, or null
ReplaySummary runReplay(const ReplaySource& source, const ReplayOptions& options, ReplayProgress* progress);

}  // namespace rmap::cli
