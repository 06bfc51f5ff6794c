#include "load/load_bench.h"

#include <cstdio>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <thread>

#include "client/http_client.h"
#include "client/metrics_sampler.h"
#include "client/percentile.h"
#include "client/query_load.h"
#include "client/robot_client.h"
#include "client/sim_feed.h"
#include "client/viewer_load.h"
#include "common/machine.h"

namespace rmap::bench {

namespace {

using json = nlohmann::json;
using client::percentile;
using client::prometheusValue;
using Clock = std::chrono::steady_clock;

constexpr double kMiB = 1 << 20;

/// The counters of /metrics the run reports as differences (the server may have run before).
const std::vector<std::string> kCounters = {"rmap_messages_acked_total",        "rmap_messages_rejected_total",
                                            "rmap_messages_refused_memory_total", "rmap_viewer_frames_sent_total",
                                            "rmap_viewer_frames_dropped_total",  "rmap_http_requests_total"};

std::map<std::string, double> counters(client::HttpClient& http) {
  const client::HttpResponse r = http.get("/metrics");
  if (r.status != 200) {
    throw std::runtime_error("GET /metrics answered " + std::to_string(r.status) + " (an admin --token is needed): " +
                             r.body);
  }
  std::map<std::string, double> out;
  for (const std::string& name : kCounters) out[name] = prometheusValue(r.body, name);
  out["rmap_resident_memory_peak_bytes"] = prometheusValue(r.body, "rmap_resident_memory_peak_bytes");
  // Quantiles since the server started: a fresh server's are the run's.
  out["server_ack_p99_s"] = client::prometheusQuantile(r.body, "rmap_ack_latency_seconds", 0.99);
  out["viewer_tick_p50_s"] = client::prometheusQuantile(r.body, "rmap_viewer_tick_seconds", 0.50);
  out["viewer_tick_p99_s"] = client::prometheusQuantile(r.body, "rmap_viewer_tick_seconds", 0.99);
  out["rmap_memory_bound_bytes"] = prometheusValue(r.body, "rmap_memory_bound_bytes");
  return out;
}

std::string mapName(const LoadBenchOptions& o, int robot) {
  return o.shared_map ? "load" : "load-" + std::to_string(robot);
}

/// Waits until every robot's map exists (robots connect on their own threads).
void waitForMaps(client::HttpClient& http, const LoadBenchOptions& o) {
  const auto deadline = Clock::now() + std::chrono::seconds(60);
  const size_t wanted = o.shared_map ? 1 : static_cast<size_t>(o.robots);
  while (Clock::now() < deadline) {
    const client::HttpResponse r = http.get("/v1/maps");
    size_t found = 0;
    if (r.status == 200) {
      const json maps = json::parse(r.body);
      for (const json& map : maps["maps"]) found += map["name"].get<std::string>().starts_with("load");
    }
    if (found >= wanted) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  throw std::runtime_error("the robots' maps did not appear within 60 s");
}

/// Points, a box page, the tile index and a tile of up to 8 maps, and the robot list.
std::vector<std::string> queryTargets(const LoadBenchOptions& o, const client::SimScene& scene) {
  const Eigen::Vector3d c = scene.world.bounds().center();
  char point[128], box[160];
  std::snprintf(point, sizeof point, "/occupancy?x=%.2f&y=%.2f&z=1.0", c.x(), c.y());
  std::snprintf(box, sizeof box, "/occupancy/box?min=%.2f,%.2f,0&max=%.2f,%.2f,3&limit=2000", c.x() - 2, c.y() - 2,
                c.x() + 2, c.y() + 2);
  std::vector<std::string> targets;
  for (int r = 0; r < std::min(o.robots, 8); r += o.shared_map ? o.robots : 1) {
    const std::string map = "/v1/maps/" + mapName(o, r);
    for (const std::string& t : {map + point, map + box, map + "/tileset.json", map + "/tiles/0/0/0/0"}) {
      targets.push_back(t);
    }
  }
  targets.push_back("/v1/robots");
  return targets;
}

}  // namespace

int runLoadBench(const LoadBenchOptions& o) {
  if (o.laser_robots < 0 || o.laser_robots > o.robots) throw std::invalid_argument("--laser-robots must be in [0, --robots]");
  if (o.stalled_viewers < 0 || o.stalled_viewers > o.viewers) {
    throw std::invalid_argument("--stalled-viewers must be in [0, --viewers]");
  }
  client::HttpClient http(o.server_url, o.token, std::chrono::milliseconds(30000));
  const std::map<std::string, double> before = counters(http);
  const client::Endpoint endpoint = client::Endpoint::parse(o.server_url);
  const std::string ws_url = "ws://" + endpoint.host + ":" + endpoint.port;

  std::cerr << "simulating the building and " << (o.robots - o.laser_robots) << " lidar robots' clouds" << std::endl;
  const client::SimScene scene = client::makeSimScene(1);
  client::SimFeedOptions feed;
  feed.server_url = ws_url;
  feed.token = o.token;
  feed.robots = o.robots - o.laser_robots;
  feed.laser2d_robots = o.laser_robots;
  feed.shared_map = o.shared_map;
  feed.map_prefix = "load";
  feed.robot_prefix = "load-robot";
  feed.rate_hz = o.rate_hz;
  feed.duration = std::chrono::milliseconds(static_cast<int64_t>(o.seconds * 1000));
  feed.lidar_rings = o.lidar_rings;
  feed.lidar_columns = o.lidar_columns;
  feed.precompute_clouds = 8;
  feed.timeout = std::chrono::milliseconds(60000);

  client::ViewerLoadOptions viewer_options;
  viewer_options.server_url = ws_url;
  viewer_options.token = o.token;
  viewer_options.reading = o.viewers - o.stalled_viewers;
  viewer_options.stalled = o.stalled_viewers;
  client::ViewerLoad viewers(viewer_options);
  client::MetricsSampler sampler(o.server_url, o.token,
                                 {"rmap_resident_memory_bytes", "rmap_viewer_queue_bytes", "rmap_viewers_skipping",
                                  "rmap_robot_connections", "rmap_commit_queue_bytes", "rmap_map_queue_messages"});

  std::cerr << o.robots << " robots at " << o.rate_hz << " messages/s for " << o.seconds << " s, " << o.viewers
            << " viewers (" << o.stalled_viewers << " stalled), " << o.query_connections << " query connections"
            << std::endl;
  const auto start = Clock::now();
  client::SimFeedResult fed;
  std::thread robots([&] { fed = client::runSimFeed(scene, feed); });
  std::optional<client::QueryLoadResult> queried;
  try {
    waitForMaps(http, o);
    client::QueryLoadOptions query_options;
    query_options.server_url = o.server_url;
    query_options.token = o.token;
    query_options.connections = o.query_connections;
    query_options.targets = queryTargets(o, scene);
    client::QueryLoad queries(query_options);
    robots.join();
    queried = queries.stop();
  } catch (...) {
    if (robots.joinable()) robots.join();
    throw;
  }
  const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // the last ticks reach the viewers
  sampler.stop();
  const std::map<std::string, double> after = counters(http);
  const client::ViewerLoadResult viewed = viewers.stop();
  const auto delta = [&](const std::string& name) { return after.at(name) - before.at(name); };

  uint64_t viewer_frames = 0, viewer_tiles = 0, viewer_resyncs = 0;
  for (const client::ViewerCounts& v : viewed.reading) {
    viewer_frames += v.frames;
    viewer_tiles += v.tiles;
    viewer_resyncs += v.resyncs;
  }
  const uint64_t messages = fed.clouds_acked + fed.scans_acked;
  const uint64_t unacked = fed.clouds_sent + fed.scans_sent - messages;
  const json results = {
      {"robots", o.robots},
      {"laser_robots", o.laser_robots},
      {"shared_map", o.shared_map},
      {"rate_hz_per_robot", o.rate_hz},
      {"lidar_rings", o.lidar_rings},
      {"lidar_columns", o.lidar_columns},
      {"wall_s", wall_s},
      {"messages_acked", messages},
      {"messages_unacked", unacked},
      {"feed_wall_s", fed.wall_s},
      {"messages_per_s", double(messages) / fed.wall_s},
      {"points_per_s", fed.clouds_sent == 0 ? 0.0
                                            : double(fed.points_sent) * double(fed.clouds_acked) /
                                                  double(fed.clouds_sent) / fed.wall_s},
      {"robot_errors", fed.errors.size()},
      {"ack_p50_ms", percentile(fed.ack_latencies_ms, 0.50)},
      {"ack_p95_ms", percentile(fed.ack_latencies_ms, 0.95)},
      {"ack_p99_ms", percentile(fed.ack_latencies_ms, 0.99)},
      {"ack_max_ms", percentile(fed.ack_latencies_ms, 1.0)},
      {"server_acked", delta("rmap_messages_acked_total")},
      {"server_ack_p99_bucket_s", after.at("server_ack_p99_s")},
      {"viewer_tick_p50_bucket_s", after.at("viewer_tick_p50_s")},
      {"viewer_tick_p99_bucket_s", after.at("viewer_tick_p99_s")},
      {"server_rejected", delta("rmap_messages_rejected_total")},
      {"server_refused_memory", delta("rmap_messages_refused_memory_total")},
      {"resident_peak_mib", after.at("rmap_resident_memory_peak_bytes") / kMiB},
      {"resident_sampled_max_mib", sampler.max("rmap_resident_memory_bytes") / kMiB},
      {"memory_bound_mib", after.at("rmap_memory_bound_bytes") / kMiB},
      {"commit_queue_max_mib", sampler.max("rmap_commit_queue_bytes") / kMiB},
      {"map_queue_max_messages", sampler.max("rmap_map_queue_messages")},
      {"robot_connections_max", sampler.max("rmap_robot_connections")},
      {"viewers", o.viewers},
      {"stalled_viewers", o.stalled_viewers},
      {"viewer_frames_sent", delta("rmap_viewer_frames_sent_total")},
      {"viewer_frames_dropped", delta("rmap_viewer_frames_dropped_total")},
      {"viewer_queue_max_mib", sampler.max("rmap_viewer_queue_bytes") / kMiB},
      {"viewers_skipping_max", sampler.max("rmap_viewers_skipping")},
      {"reading_viewer_frames_per_s", viewed.reading.empty() ? 0.0 : double(viewer_frames) / double(viewed.reading.size()) / wall_s},
      {"reading_viewer_tiles_frames", viewer_tiles},
      {"reading_viewer_resyncs", viewer_resyncs},
      {"viewer_errors", viewed.errors.size()},
      {"queries", queried->answered},
      {"queries_per_s", double(queried->answered) / queried->wall_s},
      {"query_p50_ms", percentile(queried->latencies_ms, 0.50)},
      {"query_p99_ms", percentile(queried->latencies_ms, 0.99)},
      {"query_statuses", queried->statuses},
      {"query_failures", queried->failed},
      {"machine", machineJson()}};
  for (const std::string& e : fed.errors) std::cerr << "robot error: " << e << "\n";
  for (const std::string& e : viewed.errors) std::cerr << "viewer error: " << e << "\n";
  for (const std::string& e : queried->first_errors) std::cerr << "query error: " << e << "\n";
  std::printf("robots %d  messages acked %llu (%.0f/s, %llu unacked)  ack p50/p95/p99/max %.1f/%.1f/%.1f/%.1f ms "
              "(server p99 <= %g s)\n"
              "resident peak %.0f MiB (bound %.0f MiB, 0 = none; %.0f refused for memory)\n"
              "viewer frames sent %.0f dropped %.0f (stalled viewers %d, largest viewer backlog %.2f MiB), "
              "viewer tick p50/p99 <= %g/%g s\n"
              "queries %llu (%.0f/s) p50/p99 %.1f/%.1f ms, %llu failed\n",
              o.robots, static_cast<unsigned long long>(messages), results["messages_per_s"].get<double>(),
              static_cast<unsigned long long>(unacked), results["ack_p50_ms"].get<double>(),
              results["ack_p95_ms"].get<double>(), results["ack_p99_ms"].get<double>(),
              results["ack_max_ms"].get<double>(), after.at("server_ack_p99_s"), results["resident_peak_mib"].get<double>(),
              results["memory_bound_mib"].get<double>(), results["server_refused_memory"].get<double>(),
              results["viewer_frames_sent"].get<double>(), results["viewer_frames_dropped"].get<double>(),
              o.stalled_viewers, results["viewer_queue_max_mib"].get<double>(), after.at("viewer_tick_p50_s"),
              after.at("viewer_tick_p99_s"),
              static_cast<unsigned long long>(queried->answered), results["queries_per_s"].get<double>(),
              results["query_p50_ms"].get<double>(), results["query_p99_ms"].get<double>(),
              static_cast<unsigned long long>(queried->failed));
  if (!o.json_out.empty()) std::ofstream(o.json_out) << results.dump(2) << "\n";
  return fed.errors.empty() && unacked == 0 ? 0 : 1;
}

}  // namespace rmap::bench
