// Load: one rmapd on loopback with 64 robots streaming at once (column clouds
// and 2D laser scans at a bounded rate), 32 viewers subscribed of which 8 never
// read, and HTTP queries running meanwhile. Every message must be acknowledged
// within a bounded time, durable and applied once; the server must stay under
// its memory bound and skip the stalled viewers instead of buffering for them;
// /metrics must tell what happened. Then: above the memory bound robot data is
// refused unstored, and resent under a higher bound it is stored once.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <thread>

#include "api_helpers.h"
#include "client/metrics_sampler.h"
#include "client/percentile.h"
#include "client/query_load.h"
#include "client/robot_client.h"
#include "client/sim_feed.h"
#include "client/viewer_load.h"
#include "column_clouds.h"
#include "laser_walker.h"
#include "rmapd_process.h"
#include "viewer_stream.h"

namespace rmap::testing {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

constexpr int kColumnRobots = 56;
constexpr int kLaserRobots = 8;
constexpr int kRobots = kColumnRobots + kLaserRobots;
constexpr int kColumnMaps = 4;  ///< column robots share these maps, 14 each
/// Each robot sends at least this many messages, and goes on (up to the most) until the
/// stalled viewers are being skipped: how soon depends on how fast the machine ticks.
constexpr uint64_t kCloudsPerRobot = 60;
constexpr uint64_t kMostCloudsPerRobot = 200;
constexpr double kCloudRate_hz = 8.0;
constexpr uint64_t kScansPerRobot = 30;
constexpr uint64_t kMostScansPerRobot = 100;
constexpr double kScanRate_hz = 4.0;
constexpr int kReadingViewers = 24;
constexpr int kStalledViewers = 8;
constexpr size_t kViewerQueueBytes = 64u << 10;
/// Generous: only a stall fails them, not a busy machine. The server's own measure (frame
/// read → ack queued) is the bound it keeps; the robots' adds their threads' waits for a core.
constexpr double kServerAckP99Bound_s = 2.5;  // a bucket bound of rmap_ack_latency_seconds
#ifdef RMAP_SANITIZE
// A sanitized rmapd's resident memory also holds ASan's shadow and its 256 MiB quarantine.
constexpr uint64_t kMemoryBoundBytes = uint64_t{2} << 30;
// The sanitized robots and viewers (96 threads on 2 cores in CI) run about 3x slower: there
// the robots saw p99 5.2 s while the server's own p99 stayed within 2.5 s.
constexpr double kRobotAckP99Bound_ms = 15000.0;
#else
constexpr uint64_t kMemoryBoundBytes = 512u << 20;
constexpr double kRobotAckP99Bound_ms = 5000.0;
#endif

std::string columnMap(int robot) { return "load-" + std::to_string(robot % kColumnMaps); }
/// Column of robot `robot`'s k-th cloud: distinct within its map.
uint64_t columnIndex(int robot, uint64_t k) {
  return static_cast<uint64_t>(robot / kColumnMaps) * kMostCloudsPerRobot + k;
}
std::string robotId(int robot) { return "load-bot-" + std::to_string(robot); }

/// What one robot saw of its stream.
struct RobotOutcome {
  uint64_t sent = 0;
  uint64_t acked = 0;
  uint64_t pose_estimates = 0;
  std::vector<double> ack_latencies_ms;
  std::vector<std::string> errors;
};

/// Robot `robot` from Hello to its last ack, sending at its rate until it sent its least
/// messages and `enough` is set, or its most; never throws.
void runRobot(int robot, const std::string& url, const sim::VoxelWorld& world, Clock::time_point start,
              const std::atomic<bool>& enough, RobotOutcome& out) {
  const bool laser = robot >= kColumnRobots;
  const uint64_t least = laser ? kScansPerRobot : kCloudsPerRobot;
  const uint64_t most = laser ? kMostScansPerRobot : kMostCloudsPerRobot;
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / (laser ? kScanRate_hz : kCloudRate_hz)));
  try {
    std::optional<client::Laser2dRobot> walker;
    client::RobotClientOptions options;
    options.server_url = url;
    options.hello.set_robot_id(robotId(robot));
    if (laser) {
      walker.emplace(buildingWalker(world, static_cast<int>(kMostScansPerRobot)));
      options.hello.set_map("load-laser-" + std::to_string(robot));
      *options.hello.add_sensors() = walker->sensor();
    } else {
      options.hello.set_map(columnMap(robot));
    }
    options.max_in_flight = 16;
    options.timeout = std::chrono::seconds(30);
    client::RobotClient client(options);
    // Callbacks run one at a time on the client's thread; `out` is read after close().
    client.onAck([&](const v1::Ack& ack, std::chrono::nanoseconds latency) {
      out.acked += !ack.duplicate();
      out.ack_latencies_ms.push_back(std::chrono::duration<double, std::milli>(latency).count());
    });
    client.onPose([&](const v1::PoseEstimate&) { ++out.pose_estimates; });
    client.onError([&](const v1::Error& e) { out.errors.push_back(e.code() + ": " + e.message()); });
    client.connect();
    // Robots are spread over the period, not in step.
    Clock::time_point due = start + period * robot / kRobots;
    for (uint64_t k = 0; k < most && (k < least || !enough); ++k) {
      std::this_thread::sleep_until(due);
      const int64_t stamp_ns = 1'000'000'000 + static_cast<int64_t>(k) * 100'000'000;
      v1::RobotMessage message;
      if (laser) {
        *message.mutable_scan() = walker->next().scan;
        message.mutable_scan()->set_stamp_ns(stamp_ns);
      } else {
        message = columnCloud(columnIndex(robot, k), stamp_ns);
      }
      client.send(std::move(message));
      ++out.sent;
      due = std::max(due + period, Clock::now());
    }
    if (!client.waitAllAcked(std::chrono::seconds(30))) out.errors.push_back("not every message was answered");
    client.close();
  } catch (const std::exception& e) {
    out.errors.push_back(e.what());
  }
}

/// VmHWM of a process (bytes), 0 when unreadable.
uint64_t peakResidentBytes(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stoull(line.substr(6)) * 1024;
  }
  return 0;
}

/// The queries a map viewer and a planner make: points, a box page, the tile index and tiles.
std::vector<std::string> queryTargets() {
  std::vector<std::string> targets;
  for (int m = 0; m < kColumnMaps; ++m) {
    const std::string map = "/v1/maps/load-" + std::to_string(m);
    targets.push_back(map + "/occupancy?x=0.05&y=0.05&z=2.05");
    targets.push_back(map + "/occupancy/box?min=0,0,0&max=20,4,3&limit=2000");
    targets.push_back(map + "/tileset.json");
    targets.push_back(map + "/tiles/0/0/0/0");
    targets.push_back(map + "/tiles/2/0/0/0");
  }
  targets.push_back("/v1/robots");
  return targets;
}

TEST(Load, SixtyFourRobotsThirtyTwoViewersAndQueriesStayBoundedAndLoseNothing) {
  TempDir dir("rmap-load");
  const std::string config = "viewer_tick_ms: 50\nlimits:\n  viewer_send_queue_bytes: " +
                             std::to_string(kViewerQueueBytes) + "\n  max_memory_bytes: " +
                             std::to_string(kMemoryBoundBytes) + "\n";
  RmapdProcess rmapd(dir.path() / "data", config);
  const client::SimScene scene = client::makeSimScene(5);

  client::ViewerLoadOptions viewer_options;
  viewer_options.server_url = rmapd.wsUrl();
  viewer_options.reading = kReadingViewers;
  viewer_options.stalled = kStalledViewers;
  client::ViewerLoad viewers(viewer_options);
  client::MetricsSampler sampler(rmapd.httpUrl(), {}, {"rmap_viewer_queue_bytes", "rmap_resident_memory_bytes",
                                           "rmap_robot_connections", "rmap_viewers_skipping"});

  std::vector<RobotOutcome> outcomes(kRobots);
  std::vector<std::thread> robots;
  std::atomic<bool> stalled_skipped{false};
  std::atomic<bool> robots_done{false};
  std::thread watch([&] {
    while (!robots_done && sampler.latest("rmap_viewers_skipping") < kStalledViewers) {
      std::this_thread::sleep_for(milliseconds(100));
    }
    stalled_skipped = true;
  });
  const Clock::time_point start = Clock::now() + milliseconds(500);  // every robot connected by then
  for (int r = 0; r < kRobots; ++r) {
    robots.emplace_back([&, r] { runRobot(r, rmapd.wsUrl(), scene.world, start, stalled_skipped, outcomes[r]); });
  }
  std::this_thread::sleep_until(start + milliseconds(500));  // the maps exist
  client::QueryLoadOptions query_options;
  query_options.server_url = rmapd.httpUrl();
  query_options.connections = 4;
  query_options.targets = queryTargets();
  client::QueryLoad queries(query_options);
  for (std::thread& t : robots) t.join();
  robots_done = true;
  watch.join();
  const client::QueryLoadResult query_result = queries.stop();
  std::this_thread::sleep_for(milliseconds(300));  // the last ticks reach the viewers
  sampler.stop();

  client::HttpClient http(rmapd.httpUrl());
  const std::string metrics = http.get("/metrics").body;
  const client::ViewerLoadResult viewer_result = viewers.stop();
  const double wall_s = std::chrono::duration<double>(Clock::now() - start).count();

  // Every message acknowledged, within a bounded time.
  std::vector<double> latencies_ms;
  uint64_t sent = 0, scans = 0;
  for (int r = 0; r < kRobots; ++r) {
    const RobotOutcome& o = outcomes[r];
    const bool laser = r >= kColumnRobots;
    EXPECT_TRUE(o.errors.empty()) << robotId(r) << ": " << o.errors.front();
    EXPECT_GE(o.sent, laser ? kScansPerRobot : kCloudsPerRobot) << robotId(r);
    EXPECT_EQ(o.acked, o.sent) << robotId(r);
    if (laser) {
      EXPECT_EQ(o.pose_estimates, o.sent) << robotId(r) << ": the 2D SLAM answers every scan";
    }
    latencies_ms.insert(latencies_ms.end(), o.ack_latencies_ms.begin(), o.ack_latencies_ms.end());
    sent += o.sent;
    scans += laser ? o.sent : 0;
  }
  const double p50 = client::percentile(latencies_ms, 0.50), p99 = client::percentile(latencies_ms, 0.99);
  EXPECT_LT(p99, kRobotAckP99Bound_ms) << "ack latency p50 " << p50 << " ms";
  const double server_within_bound = metricValue(
      metrics, "rmap_ack_latency_seconds_bucket{le=\"" + (std::ostringstream() << kServerAckP99Bound_s).str() + "\"}");
  EXPECT_GE(server_within_bound, 0.99 * double(sent)) << "acks within " << kServerAckP99Bound_s << " s by the server's histogram";
  std::cout << "load: " << sent << " messages from " << kRobots << " robots in " << wall_s << " s, ack p50 " << p50
            << " ms p99 " << p99 << " ms max " << client::percentile(latencies_ms, 1.0) << " ms; "
            << query_result.answered << " queries p99 " << client::percentile(query_result.latencies_ms, 0.99)
            << " ms, " << server_within_bound << " acks within " << kServerAckP99Bound_s
            << " s by the server; resident peak " << peakResidentBytes(rmapd.pid()) / (1 << 20) << " MiB; viewer frames sent "
            << metricValue(metrics, "rmap_viewer_frames_sent_total") << " dropped "
            << metricValue(metrics, "rmap_viewer_frames_dropped_total") << ", bytes per reading viewer "
            << viewer_result.reading[0].bytes << std::endl;

  // Durable and applied once: the log holds every seq, each column endpoint was hit once.
  for (int r = 0; r < kRobots; ++r) {
    EXPECT_EQ(getJson(http, "/v1/robots/" + robotId(r))["last_seq"].get<uint64_t>(), outcomes[r].sent)
        << robotId(r);
  }
  for (int m = 0; m < kColumnMaps; ++m) {
    std::vector<Eigen::Vector3d> endpoints;
    for (int r = m; r < kColumnRobots; r += kColumnMaps) {
      for (uint64_t k = 0; k < outcomes[r].sent; ++k) {
        for (const Eigen::Vector3d& p : columnEndpoints(columnIndex(r, k))) endpoints.push_back(p);
      }
    }
    const v1::OccupancyBatchResponse states = batchQuery(http, "load-" + std::to_string(m), endpoints);
    size_t once = 0;
    for (int i = 0; i < states.probabilities_size(); ++i) once += std::abs(states.probabilities(i) - oneHitProbability()) < 1e-6;
    EXPECT_EQ(once, endpoints.size()) << "map load-" << m << ": endpoint cells not hit exactly once";
  }

  // /metrics agrees with what was sent.
  EXPECT_EQ(metricValue(metrics, "rmap_messages_received_total"), double(sent + kRobots)) << "data and Hellos";
  EXPECT_EQ(metricValue(metrics, "rmap_messages_acked_total"), double(sent));
  EXPECT_EQ(metricValue(metrics, "rmap_messages_durable_total"), double(sent));
  EXPECT_EQ(metricValue(metrics, "rmap_messages_rejected_total"), 0.0);
  EXPECT_EQ(metricValue(metrics, "rmap_messages_refused_memory_total"), 0.0);
  EXPECT_EQ(metricValue(metrics, "rmap_ack_latency_seconds_count"), double(sent));
  EXPECT_EQ(metricValue(metrics, "rmap_slam2d_scans_total"), double(scans));
  EXPECT_EQ(sampler.max("rmap_robot_connections"), double(kRobots));
  EXPECT_GE(metricValue(metrics, "rmap_http_requests_total"), double(query_result.answered));

  // Under the memory bound, by the server's own account and by the kernel's.
  const uint64_t peak = peakResidentBytes(rmapd.pid());
  EXPECT_GT(peak, 0u);
  EXPECT_LT(peak, kMemoryBoundBytes);
  EXPECT_EQ(metricValue(metrics, "rmap_memory_bound_bytes"), double(kMemoryBoundBytes));
  EXPECT_LT(metricValue(metrics, "rmap_resident_memory_peak_bytes"), double(kMemoryBoundBytes));
  EXPECT_GE(metricValue(metrics, "rmap_resident_memory_peak_bytes"), sampler.max("rmap_resident_memory_bytes"));

  // Reading viewers got the map's changes; the stalled ones were skipped, their backlog bounded.
  EXPECT_TRUE(viewer_result.errors.empty()) << viewer_result.errors.front();
  ASSERT_EQ(viewer_result.reading.size(), size_t{kReadingViewers});
  for (const client::ViewerCounts& v : viewer_result.reading) {
    EXPECT_GT(v.tiles, 0u);
    EXPECT_GT(v.poses, 0u);
  }
  EXPECT_EQ(metricValue(metrics, "rmap_viewer_connections"), double(kReadingViewers + kStalledViewers));
  // Sampled during the load, not at its end: a stalled peer's socket keeps taking a little more
  // as the kernel grows its send buffer, so its queue can sink below half and end the skipping
  // after the robots stopped (seen with the slower sanitized build).
  EXPECT_GE(sampler.max("rmap_viewers_skipping"), double(kStalledViewers));
  EXPECT_GT(metricValue(metrics, "rmap_viewer_frames_dropped_total"), 0.0);
  EXPECT_LE(sampler.max("rmap_viewer_queue_bytes"), double((kReadingViewers + kStalledViewers) * kViewerQueueBytes));
  EXPECT_GT(sampler.max("rmap_viewer_queue_bytes"), double(kStalledViewers * kViewerQueueBytes / 2))
      << "the stalled viewers' queues filled up";

  // The queries were all answered meanwhile.
  EXPECT_EQ(query_result.failed, 0u) << query_result.first_errors.front();
  EXPECT_EQ(query_result.statuses.size(), 1u);
  EXPECT_EQ(query_result.statuses.count(200), 1u);
  EXPECT_GT(query_result.answered, 100u);
}

TEST(Load, AboveTheMemoryBoundRobotDataIsRefusedUnstoredAndResentLaterItIsStoredOnce) {
  TempDir dir("rmap-load-bound");
  constexpr uint64_t kMessages = 5;
  std::vector<v1::RobotMessage> clouds;
  std::vector<Eigen::Vector3d> endpoints;
  for (uint64_t i = 0; i < kMessages; ++i) {
    clouds.push_back(columnCloud(i, 1'000'000 + static_cast<int64_t>(i)));
    clouds.back().set_seq(i + 1);
    for (const Eigen::Vector3d& p : columnEndpoints(i)) endpoints.push_back(p);
  }
  client::RobotClientOptions options;
  options.hello.set_robot_id("bounded-bot");
  options.hello.set_map("bounded");
  {
    // 1 MiB: below what any rmapd holds.
    RmapdProcess rmapd(dir.path() / "data", "limits:\n  max_memory_bytes: 1048576\n");
    options.server_url = rmapd.wsUrl();
    client::RobotClient robot(options);
    std::vector<v1::Error> errors;
    robot.onError([&](const v1::Error& e) { errors.push_back(e); });
    EXPECT_EQ(robot.connect().last_durable_seq(), 0u) << "robots still connect";
    for (const v1::RobotMessage& m : clouds) robot.resend(m);
    ASSERT_TRUE(robot.waitAllAcked(std::chrono::seconds(10)));
    EXPECT_EQ(robot.ackedCount(), 0u);
    ASSERT_EQ(errors.size(), kMessages);
    for (uint64_t i = 0; i < kMessages; ++i) {
      EXPECT_EQ(errors[i].code(), "resource_exhausted");
      EXPECT_EQ(errors[i].seq(), i + 1);
      EXPECT_FALSE(errors[i].fatal());
      EXPECT_EQ(errors[i].message(),
                "the server is above its memory bound of 1 MiB; the message was not acknowledged, resend it later");
    }
    EXPECT_TRUE(robot.connected()) << "the refusal is not fatal";

    // The server keeps answering: queries, viewers, metrics; nothing was stored or applied.
    client::HttpClient http(rmapd.httpUrl());
    EXPECT_EQ(http.get("/healthz").status, 200);
    EXPECT_EQ(getJson(http, "/v1/maps/bounded")["scans"].get<uint64_t>(), 0u);
    const v1::OccupancyBatchResponse unstored = batchQuery(http, "bounded", endpoints);
    for (const int state : unstored.states()) EXPECT_EQ(state, v1::UNKNOWN);
    EXPECT_EQ(getJson(http, "/v1/robots/bounded-bot")["last_seq"].get<uint64_t>(), 0u);
    ViewerStream viewer(rmapd.port(), "bounded");
    ASSERT_TRUE(viewer.next(std::chrono::seconds(5)));
    const client::HttpResponse import = http.post("/v1/maps/other:import", "not even a tree", "application/octet-stream");
    EXPECT_EQ(import.status, 503);
    EXPECT_EQ(nlohmann::json::parse(import.body)["error"]["code"], "resource_exhausted") << import.body;
    const std::string metrics = http.get("/metrics").body;
    EXPECT_EQ(metricValue(metrics, "rmap_messages_refused_memory_total"), double(kMessages));
    EXPECT_EQ(metricValue(metrics, "rmap_imports_refused_memory_total"), 1.0);
    EXPECT_EQ(metricValue(metrics, "rmap_messages_durable_total"), 0.0);
    EXPECT_EQ(metricValue(metrics, "rmap_memory_bound_bytes"), 1048576.0);
    EXPECT_GT(metricValue(metrics, "rmap_resident_memory_bytes"), 1048576.0);
    robot.close();
  }
  // A restart with a higher bound: the resent messages are stored, once.
  RmapdProcess rmapd(dir.path() / "data", "limits:\n  max_memory_bytes: " + std::to_string(kMemoryBoundBytes) + "\n");
  options.server_url = rmapd.wsUrl();
  client::RobotClient robot(options);
  uint64_t duplicates = 0;
  robot.onAck([&](const v1::Ack& ack, std::chrono::nanoseconds) { duplicates += ack.duplicate(); });
  EXPECT_EQ(robot.connect().last_durable_seq(), 0u);
  for (const v1::RobotMessage& m : clouds) robot.resend(m);
  ASSERT_TRUE(robot.waitAllAcked(std::chrono::seconds(30)));
  EXPECT_EQ(robot.ackedCount(), kMessages);
  EXPECT_EQ(duplicates, 0u) << "none of them had been stored";
  EXPECT_FALSE(robot.lastError()) << robot.lastError()->message();
  client::HttpClient http(rmapd.httpUrl());
  const v1::OccupancyBatchResponse stored = batchQuery(http, "bounded", endpoints);
  for (const float p : stored.probabilities()) {
    EXPECT_NEAR(p, oneHitProbability(), 1e-6) << "each cloud applied once";
  }
  EXPECT_EQ(metricValue(http.get("/metrics").body, "rmap_messages_durable_total"), double(kMessages));
}

}  // namespace
}  // namespace rmap::testing
