#include "cli/replay_run.h"

#include <atomic>
#include <cstdio>
#include <mutex>
#include <thread>

#include "client/robot_client.h"

namespace rmap::cli {
namespace {

using Clock = std::chrono::steady_clock;
constexpr size_t kErrorsKept = 10;

}  // namespace

nlohmann::json ReplaySummary::toJson() const {
  return {{"server", server},
          {"map", map},
          {"robot_id", robot_id},
          {"format", format},
          {"ok", ok()},
          {"frames", frames},
          {"messages_sent", sent},
          {"messages_acked", acked},
          {"duplicates", duplicates},
          {"errors", errors},
          {"clouds", clouds},
          {"scans", scans},
          {"images", images},
          {"points", points},
          {"beams", beams},
          {"dropped_points", dropped_points},
          {"resumed_after_seq", resumed_after_seq},
          {"duration_s", duration_s},
          {"messages_per_s", duration_s > 0.0 ? static_cast<double>(acked) / duration_s : 0.0},
          {"failure", failure.empty() ? nlohmann::json(nullptr) : nlohmann::json(failure)},
          {"error_messages", error_messages},
          {"notes", notes}};
}

std::string ReplaySummary::text() const {
  std::string out;
  char line[512];
  std::snprintf(line, sizeof line, "replay %s: %s as robot %s into map %s at %s\n", ok() ? "complete" : "FAILED",
                format.c_str(), robot_id.c_str(), map.c_str(), server.c_str());
  out += line;
  std::snprintf(line, sizeof line, "  messages: %zu of %zu sent, %zu acked (%zu duplicates), %zu errors\n", sent,
                frames, acked, duplicates, errors);
  out += line;
  std::snprintf(line, sizeof line,
                "  data: %zu clouds (%llu points), %zu 2D scans (%llu returns), %zu images\n", clouds,
                static_cast<unsigned long long>(points), scans, static_cast<unsigned long long>(beams), images);
  out += line;
  std::snprintf(line, sizeof line, "  duration: %.2f s (%.1f msg/s)\n", duration_s,
                duration_s > 0.0 ? static_cast<double>(acked) / duration_s : 0.0);
  out += line;
  if (dropped_points > 0) out += "  dropped: " + std::to_string(dropped_points) + " non-finite points\n";
  if (resumed_after_seq > 0) {
    out += "  note: robot " + robot_id + " had " + std::to_string(resumed_after_seq) +
           " messages in the server already; this replay added its data again (use --robot for a new robot)\n";
  }
  for (const std::string& n : notes) out += "  note: " + n + "\n";
  for (const std::string& e : error_messages) out += "  server error: " + e + "\n";
  if (!failure.empty()) out += "  failure: " + failure + "\n";
  return out;
}

ReplaySummary runReplay(const ReplaySource& source, const ReplayOptions& options, ReplayProgress* progress) {
  ReplaySummary summary;
  summary.server = options.server_url;
  summary.map = options.map;
  summary.robot_id = options.robot_id;
  summary.format = toString(source.format);
  summary.frames = source.frames;
  summary.notes = source.notes;

  client::RobotClientOptions client_options;
  client_options.server_url = options.server_url;
  client_options.token = options.token;
  client_options.ca_file = options.ca_file;
  client_options.max_in_flight = options.max_in_flight;
  client_options.timeout = options.timeout;
  client_options.hello.set_robot_id(options.robot_id);
  client_options.hello.set_map(options.map);
  client_options.hello.set_resolution_m(options.resolution_m);
  for (const rmap::v1::SensorDescription& s : source.sensors) *client_options.hello.add_sensors() = s;

  std::atomic<size_t> acked{0}, duplicates{0}, errors{0};
  std::mutex error_mutex;
  std::vector<std::string> error_messages;
  client::RobotClient robot(client_options);
  robot.onAck([&](const rmap::v1::Ack& ack, std::chrono::nanoseconds) {
    acked.fetch_add(1);
    if (ack.duplicate()) duplicates.fetch_add(1);
  });
  robot.onError([&](const rmap::v1::Error& error) {
    errors.fetch_add(1);
    std::lock_guard lock(error_mutex);
    if (error_messages.size() < kErrorsKept) {
      error_messages.push_back(error.code() + ": " + error.message() +
                               (error.seq() ? " (seq " + std::to_string(error.seq()) + ")" : std::string()));
    }
  });

  const auto start = Clock::now();
  const auto answered = [&] { return acked.load() + errors.load(); };
  try {
    const rmap::v1::Welcome welcome = robot.connect();
    summary.resumed_after_seq = welcome.last_durable_seq();
    int64_t first_stamp = 0;
    for (size_t i = 0; i < source.frames; ++i) {
      ReplayFrame frame;
      try {
        frame = source.frame(i);
      } catch (const std::exception& e) {
        summary.failure = std::string(e.what()) + " (frame " + std::to_string(i + 1) + " of " +
                          std::to_string(source.frames) + " not sent, nor any after it)";
        break;
      }
      if (i == 0) first_stamp = frame.stamp_ns;
      if (options.rate == ReplayRate::kRealtime && frame.stamp_ns > first_stamp) {
        std::this_thread::sleep_until(start + std::chrono::nanoseconds(frame.stamp_ns - first_stamp));
      }
      // The server's per-robot rate limit refuses messages in a burst above it.
      std::this_thread::sleep_until(start + std::chrono::nanoseconds(static_cast<int64_t>(
                                                static_cast<double>(i) * 1e9 / options.max_messages_per_s)));
      const auto body = frame.message.body_case();
      try {
        robot.send(std::move(frame.message));
      } catch (const client::ClientError& e) {
        throw client::ClientError("frame " + std::to_string(i + 1) + ": " + e.what());
      }
      ++summary.sent;
      summary.dropped_points += frame.dropped_points;
      if (body == rmap::v1::RobotMessage::kCloud) {
        ++summary.clouds;
        summary.points += frame.points;
      } else if (body == rmap::v1::RobotMessage::kScan) {
        ++summary.scans;
        summary.beams += frame.points;
      } else if (body == rmap::v1::RobotMessage::kImage) {
        ++summary.images;
      }
      if (progress) progress->update(summary.sent, answered());
    }
    // Wait for the last acks in slices, so the progress keeps moving.
    const auto deadline = Clock::now() + options.timeout;
    while (!robot.waitAllAcked(std::chrono::milliseconds(200))) {
      if (!robot.connected()) throw client::ClientError("the server closed the stream before acknowledging everything");
      if (Clock::now() > deadline) {
        throw client::ClientError("timed out after " + std::to_string(options.timeout.count()) +
                                  " ms waiting for the last acknowledgements");
      }
      if (progress) progress->update(summary.sent, answered());
    }
  } catch (const client::ClientError& e) {
    if (summary.failure.empty()) summary.failure = e.what();
  }
  summary.duration_s = std::chrono::duration<double>(Clock::now() - start).count();
  if (progress) progress->finish(summary.sent, answered());
  robot.close();
  summary.acked = acked.load();
  summary.duplicates = duplicates.load();
  summary.errors = errors.load();
  {
    std::lock_guard lock(error_mutex);
    summary.error_messages = error_messages;
  }
  return summary;
}

}  // namespace rmap::cli
