#include "app/metrics.h"

#include "app/loop_closures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rmap::app {

void LatencyHistogram::observe(double seconds) {
  const auto bucket = std::lower_bound(kBoundsS.begin(), kBoundsS.end(), seconds) - kBoundsS.begin();
  buckets_[static_cast<size_t>(bucket)].fetch_add(1, std::memory_order_relaxed);
  count_.fetch_add(1, std::memory_order_relaxed);
  sum_ns_.fetch_add(static_cast<uint64_t>(std::max(0.0, seconds) * 1e9), std::memory_order_relaxed);
}

double LatencyHistogram::quantile(double q) const {
  const uint64_t total = count_.load(std::memory_order_relaxed);
  if (total == 0) return 0.0;
  const auto rank = static_cast<uint64_t>(std::ceil(q * static_cast<double>(total)));
  uint64_t seen = 0;
  for (size_t i = 0; i < kBoundsS.size(); ++i) {
    seen += buckets_[i].load(std::memory_order_relaxed);
    if (seen >= rank) return kBoundsS[i];
  }
  return INFINITY;
}

void LatencyHistogram::render(const std::string& name, const std::string& help, std::string& out) const {
  out += "# HELP " + name + " " + help + "\n# TYPE " + name + " histogram\n";
  uint64_t cumulative = 0;
  char line[160];
  for (size_t i = 0; i < kBoundsS.size(); ++i) {
    cumulative += buckets_[i].load(std::memory_order_relaxed);
    std::snprintf(line, sizeof line, "%s_bucket{le=\"%g\"} %llu\n", name.c_str(), kBoundsS[i],
                  static_cast<unsigned long long>(cumulative));
    out += line;
  }
  cumulative += buckets_.back().load(std::memory_order_relaxed);
  std::snprintf(line, sizeof line, "%s_bucket{le=\"+Inf\"} %llu\n%s_sum %.9f\n%s_count %llu\n", name.c_str(),
                static_cast<unsigned long long>(cumulative), name.c_str(),
                static_cast<double>(sum_ns_.load(std::memory_order_relaxed)) * 1e-9, name.c_str(),
                static_cast<unsigned long long>(count_.load(std::memory_order_relaxed)));
  out += line;
}

namespace {

void metric(std::string& out, const char* name, const char* type, const char* help, uint64_t value) {
  out += std::string("# HELP ") + name + " " + help + "\n# TYPE " + name + " " + type + "\n" + name + " " +
         std::to_string(value) + "\n";
}

uint64_t load(const std::atomic<uint64_t>& v) { return v.load(std::memory_order_relaxed); }

}  // namespace

std::string renderPrometheus(const Metrics& m, const MetricsGauges& g) {
  std::string out;
  out.reserve(8192);
  metric(out, "rmap_messages_received_total", "counter", "Robot frames received, valid or not.",
         load(m.messages_received));
  metric(out, "rmap_messages_rejected_total", "counter", "Robot messages refused with an error.",
         load(m.messages_rejected));
  metric(out, "rmap_messages_refused_memory_total", "counter",
         "Robot messages refused because the server was above its memory bound (not stored).",
         load(m.messages_refused_memory));
  metric(out, "rmap_imports_refused_memory_total", "counter",
         "Map imports refused because the server was above its memory bound.", load(m.imports_refused_memory));
  metric(out, "rmap_messages_acked_total", "counter", "Robot messages acknowledged by this process.",
         load(m.messages_acked));
  metric(out, "rmap_messages_duplicate_total", "counter", "Resent messages acknowledged without applying them again.",
         load(m.messages_duplicate));
  metric(out, "rmap_messages_durable_total", "counter", "Robot messages held in the store, recovered ones included.",
         load(m.messages_durable));
  metric(out, "rmap_messages_recovered_total", "counter", "Messages replayed from the store at start.",
         load(m.messages_recovered));
  metric(out, "rmap_points_integrated_total", "counter", "Points integrated into 3D maps.", load(m.points_integrated));
  metric(out, "rmap_store_failures_total", "counter", "Failed store commits (messages not acknowledged).",
         load(m.store_failures));
  metric(out, "rmap_http_requests_total", "counter", "HTTP requests answered.", load(m.http_requests));
  metric(out, "rmap_http_errors_total", "counter", "HTTP responses with status >= 400.", load(m.http_errors));
  metric(out, "rmap_viewer_frames_sent_total", "counter", "Frames queued to viewers.", load(m.viewer_frames_sent));
  metric(out, "rmap_viewer_frames_dropped_total", "counter", "Frames skipped for viewers too far behind.",
         load(m.viewer_frames_dropped));
  metric(out, "rmap_snapshots_written_total", "counter", "Map snapshots written to the store.",
         load(m.snapshots_written));
  metric(out, "rmap_slam2d_scans_total", "counter", "Laser scans taken by the 2D SLAM, replayed ones included.",
         load(m.slam2d_scans));
  metric(out, "rmap_slam2d_scans_refused_total", "counter", "Laser scans the 2D SLAM could not use.",
         load(m.slam2d_scans_refused));
  metric(out, "rmap_pose_estimates_sent_total", "counter", "PoseEstimates sent to robots.",
         load(m.pose_estimates_sent));
  out += "# HELP rmap_loop_closures_total Loop closures stored, by source.\n# TYPE rmap_loop_closures_total counter\n";
  for (LoopSource s : {LoopSource::kCamera, LoopSource::kLaserIntensity, LoopSource::kGeometry}) {
    out += std::string("rmap_loop_closures_total{source=\"") + toString(s) + "\"} " +
           std::to_string(load(m.loop_closures[static_cast<size_t>(s)])) + "\n";
  }
  metric(out, "rmap_loop_frames_total", "counter", "Frames put through place recognition, replayed ones included.",
         load(m.loop_frames));
  metric(out, "rmap_loop_frames_refused_total", "counter", "Frames place recognition could not decode.",
         load(m.loop_frames_refused));
  metric(out, "rmap_loop_frames_dropped_total", "counter",
         "Live frames skipped because place recognition was behind (acks never wait for it).",
         load(m.loop_frames_dropped));
  metric(out, "rmap_loop_closures_refused_total", "counter",
         "Place matches refused: their measured relative pose contradicts the places' poses.",
         load(m.loop_closures_refused));
  metric(out, "rmap_loop_closures_withdrawn_total", "counter",
         "Stored loop closures withdrawn: a later 2D pose graph optimisation dropped them.",
         load(m.loop_closures_withdrawn));
  metric(out, "rmap_trajectory_corrections_total", "counter",
         "2D pose graph optimisations applied to trajectories and maps.", load(m.trajectory_corrections));
  metric(out, "rmap_robot_connections", "gauge", "Open robot streams.", g.robot_connections);
  metric(out, "rmap_viewer_connections", "gauge", "Open viewer streams.", g.viewer_connections);
  metric(out, "rmap_viewers_skipping", "gauge", "Viewers too far behind whose frames are being skipped.",
         g.viewers_skipping);
  metric(out, "rmap_viewer_queue_bytes", "gauge", "Bytes queued to viewers, not yet written to their sockets.",
         g.viewer_queue_bytes);
  metric(out, "rmap_http_connections", "gauge", "Open connections (HTTP and WebSocket).", g.http_connections);
  metric(out, "rmap_commit_queue_messages", "gauge", "Messages waiting to be made durable.", g.commit_queue_messages);
  metric(out, "rmap_commit_queue_bytes", "gauge", "Bytes waiting to be made durable.", g.commit_queue_bytes);
  metric(out, "rmap_map_queue_messages", "gauge", "Durable messages waiting to be applied to maps.",
         g.map_queue_messages);
  metric(out, "rmap_loop_queue_frames", "gauge", "Frames waiting for place recognition.", g.loop_queue_frames);
  metric(out, "rmap_maps", "gauge", "Maps held.", g.maps);
  metric(out, "rmap_map_cuboids", "gauge", "Cuboids over all maps.", g.cuboids);
  metric(out, "rmap_map_memory_bytes", "gauge", "Bytes held by all maps.", g.map_memory_bytes);
  metric(out, "rmap_resident_memory_bytes", "gauge", "Resident memory of the server process.",
         g.resident_memory_bytes);
  metric(out, "rmap_resident_memory_peak_bytes", "gauge", "Peak resident memory of the server process since start.",
         g.resident_memory_peak_bytes);
  metric(out, "rmap_memory_bound_bytes", "gauge",
         "Resident memory above which robot data is refused (limits.max_memory_bytes; 0 = none).",
         g.memory_bound_bytes);
  m.ack_latency.render("rmap_ack_latency_seconds", "From a robot frame's arrival to its acknowledgement.", out);
  m.apply_latency.render("rmap_apply_latency_seconds", "Time to apply one message to its map.", out);
  m.http_latency.render("rmap_http_request_seconds", "Time to answer an HTTP request.", out);
  m.slam2d_scan_latency.render("rmap_slam2d_scan_seconds", "Time of one scan in the 2D SLAM (matching, map update).",
                               out);
  m.loop_frame_latency.render("rmap_loop_frame_seconds", "Time of one frame in place recognition (decoding included).",
                              out);
  m.correction_latency.render("rmap_trajectory_correction_seconds",
                              "Time to store corrected trajectories and re-render the 3D map's planar rows.", out);
  m.viewer_tick_latency.render("rmap_viewer_tick_seconds",
                               "Time of one viewer tick: tile changes of every map scanned and pushed with the poses.", out);
  return out;
}

}  // namespace rmap::app
