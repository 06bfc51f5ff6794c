// `rmap replay`: streams datasets on disk to rmapd as one robot (see docs/CLI.md).

#include <unistd.h>

#include <fstream>
#include <iostream>

#include "cli/commands.h"
#include "cli/replay_run.h"
#include "cli/replay_source.h"

namespace rmap::cli {

void addReplayCommand(CLI::App& app, int& exit_code) {
  struct Args {
    std::string server = "ws://127.0.0.1:8080";
    std::string map;
    std::string robot;
    std::string token;
    std::string ca_file;
    std::string format = "auto";
    std::string rate = "max";
    std::string json_out;
    double resolution_m = 0.0;
    size_t max_in_flight = 64;
    double max_rate = 1000.0;
    double timeout_s = 60.0;
    bool quiet = false;
    ReplaySourceOptions source;
    std::vector<std::string> files;
  };
  auto args = std::make_shared<Args>();
  CLI::App* replay = app.add_subcommand(
      "replay", "stream datasets to a server as one robot: CARMEN logs, OctoMap .graph, scan.dat text clouds, "
                "velodyne .bin, PLY/PCD clouds, 3DTK folders, image folders");
  replay->add_option("--server", args->server, "robot stream endpoint ws://HOST:PORT or wss://HOST:PORT")
      ->capture_default_str();
  replay->add_option("--map", args->map, "map to write to (created on first use)")->required();
  replay->add_option("--robot", args->robot, "robot id (default: the first file's name without extensions)");
  replay->add_option("--token", args->token, "bearer token of a robot or admin role");
  replay->add_option("--ca-file", args->ca_file, "wss://: PEM CA certificates rmapd's certificate must chain to "
                     "(default: the system's trust store)");
  std::vector<std::string> formats{"auto"};
  formats.insert(formats.end(), replayFormatNames().begin(), replayFormatNames().end());
  replay->add_option("--format", args->format, "the files' format (auto: by extension or folder content)")
      ->check(CLI::IsMember(formats))
      ->capture_default_str();
  replay->add_option("--rate", args->rate, "realtime (dataset stamps) or max (as fast as acks allow)")
      ->check(CLI::IsMember({"realtime", "max"}))
      ->capture_default_str();
  replay->add_option("--poses", args->source.poses_path,
                     "poses of .bin/.ply/.pcd/image frames, one per frame: KITTI 3x4 or TUM 'stamp x y z qx qy qz qw'");
  replay->add_option("--resolution", args->resolution_m, "cell edge of a new map, metres (0: server default)")
      ->check(CLI::NonNegativeNumber);
  replay->add_option("--period", args->source.period_s, "seconds between frames without stamps")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  replay->add_option("--laser-height", args->source.laser_height_m,
                     "CARMEN: laser height above the floor, metres (the planar cloud's z in the 3D map)")
      ->capture_default_str();
  replay->add_option("--max-in-flight", args->max_in_flight, "unacknowledged messages at most")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  replay->add_option("--max-rate", args->max_rate,
                     "messages per second at most (rmapd refuses more than 2000/s per robot by default)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  replay->add_option("--timeout", args->timeout_s, "seconds to wait for the connection and for acks")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  replay->add_option("--json", args->json_out, "also write the summary as JSON to this file");
  replay->add_flag("--quiet", args->quiet, "no progress on stderr");
  replay->add_option("files", args->files, "dataset files or folders")->required();

  replay->callback([args, &exit_code] {
    exit_code = 1;
    ReplaySource source;
    try {
      const ReplayFormat format =
          args->format == "auto" ? detectReplayFormat(args->files) : parseReplayFormat(args->format);
      source = openReplaySource(format, args->files, args->source);
    } catch (const std::exception& e) {
      std::cerr << "rmap replay: " << e.what() << "\nnothing was sent" << std::endl;
      return;
    }
    ReplayOptions options;
    options.server_url = args->server;
    options.token = args->token;
    options.ca_file = args->ca_file;
    options.map = args->map;
    options.robot_id = args->robot.empty() ? defaultRobotId(args->files.front()) : args->robot;
    options.resolution_m = args->resolution_m;
    options.rate = args->rate == "realtime" ? ReplayRate::kRealtime : ReplayRate::kMax;
    options.max_in_flight = args->max_in_flight;
    options.max_messages_per_s = args->max_rate;
    options.timeout = std::chrono::milliseconds(static_cast<int64_t>(args->timeout_s * 1000.0));
    if (source.reads_per_frame) {
      source.notes.push_back("frames are read one file at a time; each file is parsed whole before it is sent");
    }
    std::unique_ptr<ReplayProgress> progress;
    if (!args->quiet) progress = std::make_unique<ReplayProgress>(std::cerr, isatty(STDERR_FILENO) == 1, source.frames);
    const ReplaySummary summary = runReplay(source, options, progress.get());
    std::cout << summary.text() << std::flush;
    if (!args->json_out.empty()) {
      std::ofstream out(args->json_out);
      out << summary.toJson().dump(2) << "\n";
      if (!out) {
        std::cerr << "rmap replay: cannot write " << args->json_out << std::endl;
        return;
      }
    }
    exit_code = summary.ok() ? 0 : 1;
  });
}

}  // namespace rmap::cli
