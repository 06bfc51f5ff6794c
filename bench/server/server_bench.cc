#include "server/server_bench.h"

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>
#include <thread>

#include "app/mapping_service.h"
#include "app/rmapd_service.h"
#include "client/http_client.h"
#include "client/percentile.h"
#include "client/sim_feed.h"
#include "common/machine.h"
#include "net/server.h"
#include "rmap/v1/map_api.pb.h"

namespace rmap::bench {

namespace {

using json = nlohmann::json;
using client::percentile;
using Clock = std::chrono::steady_clock;

/// Figures of one streaming phase.
json feedJson(const client::SimFeedResult& r) {
  const double points_acked =
      r.clouds_sent == 0 ? 0.0 : double(r.points_sent) * double(r.clouds_acked) / double(r.clouds_sent);
  return {{"clouds_acked", r.clouds_acked},
          {"wall_s", r.wall_s},
          {"clouds_per_s", double(r.clouds_acked) / r.wall_s},
          {"points_per_s", points_acked / r.wall_s},
          {"ack_p50_ms", percentile(r.ack_latencies_ms, 0.50)},
          {"ack_p99_ms", percentile(r.ack_latencies_ms, 0.99)},
          {"errors", r.errors.size()}};
}

/// Random points in the building's box (half of them in free or occupied space).
std::vector<Eigen::Vector3d> queryPoints(const client::SimScene& scene, size_t n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  const Eigen::AlignedBox3d box = scene.world.bounds();
  std::vector<Eigen::Vector3d> points(n);
  for (auto& p : points) {
    for (int a = 0; a < 3; ++a) {
      p[a] = std::uniform_real_distribution<double>(box.min()[a], box.max()[a])(rng);
    }
  }
  return points;
}

double pointQueriesPerS(const std::string& url, const std::string& map, const client::SimScene& scene,
                        int connections, double seconds) {
  std::atomic<uint64_t> answered{0};
  std::atomic<bool> failed{false};
  std::vector<std::thread> threads;
  const auto start = Clock::now();
  const auto end = start + std::chrono::duration<double>(seconds);
  for (int c = 0; c < connections; ++c) {
    threads.emplace_back([&, c] {
      client::HttpClient http(url);
      const std::vector<Eigen::Vector3d> points = queryPoints(scene, 4096, 100 + c);
      char target[256];
      for (size_t i = 0; Clock::now() < end; ++i) {
        const Eigen::Vector3d& p = points[i % points.size()];
        std::snprintf(target, sizeof target, "/v1/maps/%s/occupancy?x=%.3f&y=%.3f&z=%.3f", map.c_str(), p.x(), p.y(),
                      p.z());
        if (http.get(target).status != 200) failed = true;
        answered.fetch_add(1, std::memory_order_relaxed);
      }
    });
  }
  for (auto& t : threads) t.join();
  if (failed) std::cerr << "warning: some point queries failed\n";
  return double(answered) / std::chrono::duration<double>(Clock::now() - start).count();
}

double batchPointsPerS(const std::string& url, const std::string& map, const client::SimScene& scene, int n,
                       double seconds) {
  v1::OccupancyBatchRequest request;
  for (const Eigen::Vector3d& p : queryPoints(scene, static_cast<size_t>(n), 7)) {
    for (int a = 0; a < 3; ++a) request.add_xyz_m(p[a]);
  }
  const std::string body = request.SerializeAsString();
  client::HttpClient http(url, {}, std::chrono::milliseconds(60000));
  uint64_t points = 0;
  const auto start = Clock::now();
  while (Clock::now() - start < std::chrono::duration<double>(seconds)) {
    const client::HttpResponse r = http.post("/v1/maps/" + map + "/occupancy:batch", body, "application/x-protobuf");
    v1::OccupancyBatchResponse response;
    if (r.status != 200 || !response.ParseFromString(r.body) || response.states_size() != n) {
      throw std::runtime_error("batch query failed: " + std::to_string(r.status));
    }
    points += static_cast<uint64_t>(n);
  }
  return double(points) / std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace

int runServerBench(const ServerBenchOptions& o) {
  const std::filesystem::path data_dir =
      std::filesystem::temp_directory_path() / ("rmap-bench-server-" + std::to_string(::getpid()));
  std::filesystem::remove_all(data_dir);
  app::Config config;
  config.data_dir = data_dir;
  config.maps.resolution_m = o.resolution_m;
  config.maps.insert_threads = o.insert_threads;
  json results;
  {
    app::MappingService service(config);
    app::RmapdService handlers(service);
    net::ServerOptions server_options;
    server_options.port = 0;
    server_options.io_threads = config.io_threads;
    net::Server server(server_options, handlers);
    server.start();
    const std::string http_url = "http://127.0.0.1:" + std::to_string(server.port());
    const std::string ws_url = "ws://127.0.0.1:" + std::to_string(server.port());
    const client::SimScene scene = client::makeSimScene(1, o.resolution_m);

    client::SimFeedOptions feed;
    feed.server_url = ws_url;
    feed.robots = o.robots;
    feed.shared_map = o.shared_map;
    feed.map_prefix = "bench";
    feed.resolution_m = o.resolution_m;
    feed.rate_hz = 0.0;
    feed.duration = std::chrono::milliseconds(static_cast<int64_t>(o.phase_s * 1000));
    feed.precompute_clouds = o.precompute_clouds;
    feed.lidar_rings = o.lidar_rings;
    feed.lidar_columns = o.lidar_columns;
    feed.max_in_flight = 16;
    feed.timeout = std::chrono::milliseconds(60000);

    std::cerr << "phase 1: " << o.robots << " robots as fast as acknowledgements allow" << std::endl;
    const client::SimFeedResult max_load = client::runSimFeed(scene, feed);
    const json max_json = feedJson(max_load);
    std::cerr << "  " << max_json.dump() << std::endl;

    // Half of the maximum message rate, spread evenly over the robots.
    client::SimFeedOptions half = feed;
    half.rate_hz = 0.5 * max_json["clouds_per_s"].get<double>() / o.robots;
    half.seed = 2;
    std::cerr << "phase 2: half load, " << half.rate_hz << " clouds/s per robot" << std::endl;
    const client::SimFeedResult half_load = client::runSimFeed(scene, half);
    const json half_json = feedJson(half_load);
    std::cerr << "  " << half_json.dump() << std::endl;

    const std::string query_map = o.shared_map ? "bench" : "bench-0";
    std::cerr << "phase 3: point queries on " << o.query_connections << " keep-alive connections during half-load ingest"
              << std::endl;
    client::SimFeedOptions background = half;
    background.seed = 3;
    client::SimFeedResult background_result;
    std::thread ingest([&] { background_result = client::runSimFeed(scene, background); });
    const double point_qps = pointQueriesPerS(http_url, query_map, scene, o.query_connections, o.phase_s * 0.8);
    ingest.join();
    std::cerr << "  " << point_qps << " queries/s; ingest meanwhile " << feedJson(background_result).dump() << std::endl;

    std::cerr << "phase 4: batch queries of " << o.batch_points << " points (protobuf)" << std::endl;
    const double batch_pps = batchPointsPerS(http_url, query_map, scene, o.batch_points, o.phase_s * 0.5);
    std::cerr << "  " << batch_pps << " points/s" << std::endl;

    results = {{"robots", o.robots},
               {"shared_map", o.shared_map},
               {"resolution_m", o.resolution_m},
               {"points_per_cloud", max_load.clouds_sent ? max_load.points_sent / max_load.clouds_sent : 0},
               {"points_per_s", max_json["points_per_s"]},
               {"ack_p50_ms", half_json["ack_p50_ms"]},
               {"ack_p99_ms", half_json["ack_p99_ms"]},
               {"point_queries_per_s", point_qps},
               {"batch_points_per_s", batch_pps},
               {"max_load", max_json},
               {"half_load", half_json},
               {"ingest_during_queries", feedJson(background_result)},
               {"machine", machineJson()}};
    server.stop();
  }
  std::filesystem::remove_all(data_dir);
  std::cout << "robots " << results["robots"] << "  points/s " << results["points_per_s"] << "  ack p50/p99 (half load) "
            << results["ack_p50_ms"] << "/" << results["ack_p99_ms"] << " ms  point queries/s "
            << results["point_queries_per_s"] << "  batch points/s " << results["batch_points_per_s"] << std::endl;
  if (!o.json_out.empty()) std::ofstream(o.json_out) << results.dump(2) << "\n";
  return 0;
}

}  // namespace rmap::bench
