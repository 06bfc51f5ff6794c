// rmap-sim: simulated robots in a procedural building streaming to rmapd over
// the robot stream: lidar robots send 3D clouds, 2D-laser robots send laser
// scans with odometry and get their pose from the server's 2D SLAM.
//
//   rmap-sim --server ws://HOST:PORT --robots N [--laser2d-robots M [--laser2d-model sick|hokuyo]]
//            --duration SECONDS [--json FILE]
//
// Progress (once a second) goes to stderr, the summary to stdout (with the 2D
// robots' pose error against the truth). Exit code 0 when every sent message
// was acknowledged without errors, 1 otherwise, 2 for bad arguments.

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
  CLI::App app{"rmap-sim: simulated lidar and 2D-laser robots streaming to rmapd"};
  SimFeedOptions options;
  std::string laser2d_model = "sick";
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
  app.add_option("--robots", options.robots, "simulated lidar robots (one connection and thread each)")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000));
  app.add_option("--laser2d-robots", options.laser2d_robots,
                 "simulated 2D-laser robots on the ground storey (scans + odometry; the server's 2D SLAM tracks them)")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000));
  app.add_option("--laser2d-model", laser2d_model, "2D laser scanner: sick (SICK LMS1xx-like) or hokuyo (UTM-30LX-like)")
      ->capture_default_str()
      ->check(CLI::IsMember({"sick", "hokuyo"}));
  app.add_option("--duration", duration_s, "seconds of streaming")->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--token", options.token, "bearer token");
  app.add_option("--map", options.map_prefix, "map name (prefix with --separate-maps)")->capture_default_str();
  app.add_flag("--separate-maps", separate_maps, "robot i writes map <map>-<i> instead of one shared map");
  app.add_option("--rate", options.rate_hz, "clouds or scans per second per robot, 0 = as fast as acks allow")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--resolution", options.resolution_m, "map resolution and simulated voxel size, metres")
      ->capture_default_str()
      ->check(CLI::Range(0.02, 0.5));
  app.add_option("--seed", seed, "building and trajectory seed")->capture_default_str();
  app.add_option("--max-clouds", options.max_clouds, "stop each robot after this many clouds or scans, 0 = no limit")
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
  if (options.robots + options.laser2d_robots < 1) {
    std::fprintf(stderr, "rmap-sim: --robots plus --laser2d-robots must be at least 1\n");
    return 2;
  }
  options.laser2d_model =
      laser2d_model == "hokuyo" ? rmap::sim::Laser2dModel::hokuyoLike() : rmap::sim::Laser2dModel::sickLike();
  options.shared_map = !separate_maps;
  options.seed = seed;
  options.duration = std::chrono::milliseconds(static_cast<int64_t>(std::llround(duration_s * 1000.0)));
  const bool lasers = options.laser2d_robots > 0;
  options.on_progress = [lasers](const rmap::client::SimFeedProgress& p) {
    std::fprintf(stderr, "rmap-sim: %5.1f s  clouds sent %llu  acked %llu  points acked %llu", p.elapsed_s,
                 static_cast<unsigned long long>(p.clouds_sent), static_cast<unsigned long long>(p.clouds_acked),
                 static_cast<unsigned long long>(p.points_acked));
    if (lasers) {
      std::fprintf(stderr, "  scans sent %llu  2D SLAM poses %llu, mean error %.3f m",
                   static_cast<unsigned long long>(p.scans_sent), static_cast<unsigned long long>(p.pose_estimates),
                   p.pose_error_mean_m);
    }
    std::fprintf(stderr, "\n");
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
  if (lasers) {
    char errors[128] = "no error to report";
    if (result.pose_estimates > 0) {
      std::snprintf(errors, sizeof errors, "error vs truth mean %.3f m  max %.3f m  heading max %.4f rad",
                    result.pose_error_mean_m, result.pose_error_max_m, result.heading_error_max_rad);
    }
    std::printf("laser2d robots %d (%s)  scans sent %llu  acked %llu  2D SLAM poses %llu  %s\n", options.laser2d_robots,
                options.laser2d_model.name.c_str(), static_cast<unsigned long long>(result.scans_sent),
                static_cast<unsigned long long>(result.scans_acked),
                static_cast<unsigned long long>(result.pose_estimates), errors);
  }

  if (!json_path.empty()) {
    const nlohmann::json summary = {
        {"robots", options.robots},         {"clouds_sent", result.clouds_sent},
        {"clouds_acked", result.clouds_acked}, {"points_sent", result.points_sent},
        {"ack_p50_ms", orNull(p50)},        {"ack_p99_ms", orNull(p99)},
        {"wall_s", result.wall_s},          {"errors", result.errors},
        {"laser2d_robots", options.laser2d_robots},
        {"laser2d_model", options.laser2d_model.name},
        {"scans_sent", result.scans_sent},
        {"scans_acked", result.scans_acked},
        {"pose_estimates", result.pose_estimates},
        {"pose_error_mean_m", result.pose_estimates > 0 ? nlohmann::json(result.pose_error_mean_m) : nlohmann::json()},
        {"pose_error_max_m", result.pose_estimates > 0 ? nlohmann::json(result.pose_error_max_m) : nlohmann::json()},
        {"heading_error_max_rad",
         result.pose_estimates > 0 ? nlohmann::json(result.heading_error_max_rad) : nlohmann::json()},
    };
    std::ofstream out(json_path);
    out << summary.dump(2) << "\n";
    if (!out) {
      std::fprintf(stderr, "rmap-sim: cannot write %s\n", json_path.c_str());
      return 1;
    }
  }
  return result.errors.empty() && result.clouds_acked == result.clouds_sent && result.scans_acked == result.scans_sent
             ? 0
             : 1;
}
