// rmap-sim: simulated lidar robots in a procedural building streaming clouds
// to rmapd over the robot stream.
//
//   rmap-sim --server ws://HOST:PORT --robots N --duration SECONDS [--json FILE]
//
// Progress (once a second) goes to stderr, the summary to stdout. Exit code 0
// when every sent cloud was acknowledged without errors, 1 otherwise, 2 for
// bad arguments.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

#include "client/robot_client.h"
#include "client/sim_feed.h"

namespace {

using rmap::client::SimFeedOptions;
using rmap::client::SimFeedResult;

/// Nearest-rank percentile (p in (0, 100]) of unsorted samples; nothing when empty.
std::optional<double> percentile(std::vector<double> samples, double p) {
  if (samples.empty()) return std::nullopt;
  const size_t rank = static_cast<size_t>(std::ceil(p / 100.0 * static_cast<double>(samples.size())));
  const size_t index = std::clamp<size_t>(rank, 1, samples.size()) - 1;
  std::nth_element(samples.begin(), samples.begin() + static_cast<std::ptrdiff_t>(index), samples.end());
  return samples[index];
}

nlohmann::json orNull(const std::optional<double>& value) { return value ? nlohmann::json(*value) : nlohmann::json(); }

std::string formatMs(const std::optional<double>& value) {
  char text[32];
  if (!value) return "-";
  std::snprintf(text, sizeof text, "%.2f ms", *value);
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rmap-sim: simulated lidar robots streaming point clouds to rmapd"};
  SimFeedOptions options;
  double duration_s = 10.0;
  bool separate_maps = false;
  uint64_t seed = 1;
  std::string json_path;
  const CLI::Validator url_check(
      [](std::string& url) {
        try {
          rmap::client::Endpoint::parse(url);
          return std::string();
        } catch (const rmap::client::ClientError& e) {
          return std::string(e.what());
        }
      },
      "URL");
  app.add_option("--server", options.server_url, "rmapd robot stream, ws://HOST:PORT")
      ->capture_default_str()
      ->check(url_check);
  app.add_option("--robots", options.robots, "simulated robots (one connection and thread each)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  app.add_option("--duration", duration_s, "seconds of streaming")->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--token", options.token, "bearer token");
  app.add_option("--map", options.map_prefix, "map name (prefix with --separate-maps)")->capture_default_str();
  app.add_flag("--separate-maps", separate_maps, "robot i writes map <map>-<i> instead of one shared map");
  app.add_option("--rate", options.rate_hz, "clouds per second per robot, 0 = as fast as acks allow")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--resolution", options.resolution_m, "map resolution and simulated voxel size, metres")
      ->capture_default_str()
      ->check(CLI::Range(0.02, 0.5));
  app.add_option("--seed", seed, "building and trajectory seed")->capture_default_str();
  app.add_option("--max-clouds", options.max_clouds, "stop each robot after this many clouds, 0 = no limit")
      ->capture_default_str();
  app.add_option("--lidar-rings", options.lidar_rings, "lidar rings")->capture_default_str()->check(CLI::Range(1, 256));
  app.add_option("--lidar-columns", options.lidar_columns, "lidar beams per ring")
      ->capture_default_str()
      ->check(CLI::Range(1, 8192));
  app.add_option("--poses", options.poses, "trajectory poses per robot (clouds cycle over them)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  app.add_option("--max-in-flight", options.max_in_flight, "unacknowledged clouds per robot before sending blocks")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  app.add_option("--precompute", options.precompute_clouds,
                 "simulate at most N distinct clouds per robot and cycle over them (benchmarks), 0 = off")
      ->capture_default_str();
  app.add_option("--json", json_path, "write the summary as JSON to FILE");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  options.shared_map = !separate_maps;
  options.seed = seed;
  options.duration = std::chrono::milliseconds(static_cast<int64_t>(std::llround(duration_s * 1000.0)));
  options.on_progress = [](const rmap::client::SimFeedProgress& p) {
    std::fprintf(stderr, "rmap-sim: %5.1f s  clouds sent %llu  acked %llu  points acked %llu\n", p.elapsed_s,
                 static_cast<unsigned long long>(p.clouds_sent), static_cast<unsigned long long>(p.clouds_acked),
                 static_cast<unsigned long long>(p.points_acked));
  };

  SimFeedResult result;
  try {
    const rmap::client::SimScene scene = rmap::client::makeSimScene(seed, options.resolution_m);
    result = rmap::client::runSimFeed(scene, options);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "rmap-sim: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rmap-sim: %s\n", e.what());
    return 1;
  }

  const std::optional<double> p50 = percentile(result.ack_latencies_ms, 50.0);
  const std::optional<double> p99 = percentile(result.ack_latencies_ms, 99.0);
  for (const std::string& error : result.errors) std::fprintf(stderr, "rmap-sim: error: %s\n", error.c_str());
  std::printf("robots %d  clouds sent %llu  acked %llu  points sent %llu  ack p50 %s  p99 %s  wall %.2f s  errors %zu\n",
              options.robots, static_cast<unsigned long long>(result.clouds_sent),
              static_cast<unsigned long long>(result.clouds_acked), static_cast<unsigned long long>(result.points_sent),
              formatMs(p50).c_str(), formatMs(p99).c_str(), result.wall_s, result.errors.size());

  if (!json_path.empty()) {
    const nlohmann::json summary = {
        {"robots", options.robots},         {"clouds_sent", result.clouds_sent},
        {"clouds_acked", result.clouds_acked}, {"points_sent", result.points_sent},
        {"ack_p50_ms", orNull(p50)},        {"ack_p99_ms", orNull(p99)},
        {"wall_s", result.wall_s},          {"errors", result.errors},
    };
    std::ofstream out(json_path);
    out << summary.dump(2) << "\n";
    if (!out) {
      std::fprintf(stderr, "rmap-sim: cannot write %s\n", json_path.c_str());
      return 1;
    }
  }
  return result.errors.empty() && result.clouds_acked == result.clouds_sent ? 0 : 1;
}
