#pragma once
/// @file metrics.h
/// Counters and latency histograms of rmapd, rendered in the Prometheus text
/// exposition format by GET /metrics. Lock-free to update from any thread.

#include <array>
#include <atomic>
#include <cstdint>
#include <string>

namespace rmap::app {

/// Cumulative histogram with fixed bucket bounds in seconds.
class LatencyHistogram {
 public:
  static constexpr std::array<double, 14> kBoundsS = {0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05,
                                                      0.1,    0.25,  0.5,    1.0,   2.5,  5.0,  10.0};
  void observe(double seconds);
  /// Appends the `_bucket`, `_sum` and `_count` lines of `name`.
  void render(const std::string& name, const std::string& help, std::string& out) const;
  /// Quantile estimate (upper bucket bound), seconds; 0 when empty.
  double quantile(double q) const;

 private:
  std::array<std::atomic<uint64_t>, kBoundsS.size() + 1> buckets_{};
  std::atomic<uint64_t> count_{0};
  std::atomic<uint64_t> sum_ns_{0};
};

struct Metrics {
  std::atomic<uint64_t> messages_received{0};   ///< frames from robots, valid or not
  std::atomic<uint64_t> messages_rejected{0};   ///< refused with an Error
  std::atomic<uint64_t> messages_refused_memory{0};  ///< of those, refused above the memory bound
  std::atomic<uint64_t> messages_acked{0};      ///< acknowledged by this process (duplicates included)
  std::atomic<uint64_t> messages_duplicate{0};
  std::atomic<uint64_t> messages_durable{0};    ///< held in the store (recovered ones included)
  std::atomic<uint64_t> messages_recovered{0};  ///< replayed from the store at start
  std::atomic<uint64_t> points_integrated{0};
  std::atomic<uint64_t> store_failures{0};
  std::atomic<uint64_t> http_requests{0};
  std::atomic<uint64_t> http_errors{0};         ///< responses with status >= 400
  std::atomic<uint64_t> viewer_frames_sent{0};
  std::atomic<uint64_t> viewer_frames_dropped{0};
  std::atomic<uint64_t> imports_refused_memory{0};  ///< map imports refused above the memory bound
  std::atomic<uint64_t> snapshots_written{0};
  std::atomic<uint64_t> slam2d_scans{0};          ///< laser scans the 2D SLAM took (replayed ones included)
  std::atomic<uint64_t> slam2d_scans_refused{0};  ///< laser scans the 2D SLAM could not use
  std::atomic<uint64_t> pose_estimates_sent{0};   ///< PoseEstimates queued to robots
  /// Loop closures stored, indexed by LoopSource.
  std::array<std::atomic<uint64_t>, 3> loop_closures{};
  std::atomic<uint64_t> loop_frames{0};          ///< frames put through a place recognizer (replayed ones included)
  std::atomic<uint64_t> loop_frames_refused{0};  ///< frames that could not be made into a grey image
  std::atomic<uint64_t> loop_frames_dropped{0};  ///< live frames dropped because place recognition was behind
  /// matches refused because their measured relative pose contradicts the places' poses
  std::atomic<uint64_t> loop_closures_refused{0};
  std::atomic<uint64_t> loop_closures_withdrawn{0};  ///< stored closures a later 2D pose graph optimisation dropped
  std::atomic<uint64_t> trajectory_corrections{0};  ///< 2D pose graph optimisations applied to trajectories and maps
  LatencyHistogram ack_latency;      ///< frame received → ack queued
  LatencyHistogram apply_latency;    ///< one message applied to its map
  LatencyHistogram http_latency;
  LatencyHistogram slam2d_scan_latency;  ///< one scan through the 2D SLAM (scan matching and map update)
  LatencyHistogram loop_frame_latency;   ///< one frame through a place recognizer (decoding included)
  LatencyHistogram correction_latency;   ///< corrected trajectories stored and the 3D map's planar rows re-rendered
  LatencyHistogram viewer_tick_latency;  ///< one viewer tick: every map's tile changes scanned and pushed
};

/// Gauges read at scrape time.
struct MetricsGauges {
  uint64_t robot_connections = 0;
  uint64_t viewer_connections = 0;
  uint64_t viewers_skipping = 0;     ///< viewers whose frames are being skipped (they owe a resync)
  uint64_t viewer_queue_bytes = 0;   ///< bytes queued to all viewers, not yet written to their sockets
  uint64_t http_connections = 0;
  uint64_t commit_queue_messages = 0;
  uint64_t commit_queue_bytes = 0;
  uint64_t map_queue_messages = 0;
  uint64_t loop_queue_frames = 0;
  uint64_t maps = 0;
  uint64_t cuboids = 0;
  uint64_t map_memory_bytes = 0;
  uint64_t resident_memory_bytes = 0;       ///< the process's resident set
  uint64_t resident_memory_peak_bytes = 0;  ///< its peak since start
  uint64_t memory_bound_bytes = 0;          ///< limits.max_memory_bytes, 0 = none
};

std::string renderPrometheus(const Metrics& metrics, const MetricsGauges& gauges);

}  // namespace rmap::app
