// kill -9 at random moments of ingest, 24 times over on one data directory.
// Two robots stream clouds into one map and a third streams 2D laser scans
// into another. After every kill a copy of the database passes SQLite's
// integrity check and logs each robot's seqs 1..D once, every acknowledged
// seq among them; after every restart the map holds exactly the logged
// messages, each applied once; every unacknowledged message resent with its
// old seq is acked as a duplicate when it was logged and applied once either way.
//
// The moments are random: the seed is printed, RMAP_FAULT_SEED=<seed> repeats
// the same delays (the rest depends on timing).
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <iterator>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <thread>

#include "api_helpers.h"
#include "client/robot_client.h"
#include "column_clouds.h"
#include "laser_walker.h"
#include "rmapd_process.h"
#include "sim/building.h"
#include "store_copy.h"

namespace rmap::testing {
namespace {

constexpr int kCycles = 24;
constexpr const char* kCloudMap = "cycles";
constexpr const char* kScanMap = "cycles-2d";

// Snapshots every 0.2 s, so kills land before, during and after them too;
// fusion tolerance 0 keeps every cell's probability exact.
constexpr const char* kFaultConfig = R"(
snapshot_interval_s: 0.2
maps:
  fusion_tolerance_log_odds: 0
loop_closure: {camera: false, cloud_intensity: false, reflectivity_patches: false}
)";

/// One robot over all cycles: what it sent and what the server acknowledged.
struct Track {
  std::string robot_id;
  std::string map;
  std::function<v1::RobotMessage(uint64_t seq)> message;  ///< the same content on every resend of a seq
  size_t max_new_per_cycle = SIZE_MAX;
  std::chrono::milliseconds pace{0};  ///< between new messages
  std::optional<v1::SensorDescription> sensor;

  uint64_t highest_sent = 0;
  uint64_t last_durable = 0;  ///< Welcome of the current session
  std::mutex mutex;           ///< guards the sets below (written by the ack callback)
  std::set<uint64_t> acked;   ///< over all cycles
  std::vector<std::string> problems;
  uint64_t fresh_acks = 0;
  uint64_t duplicate_acks = 0;
  std::unique_ptr<client::RobotClient> client;

  void connect(const std::string& url) {
    client::RobotClientOptions options;
    options.server_url = url;
    options.hello.set_robot_id(robot_id);
    options.hello.set_map(map);
    if (sensor) *options.hello.add_sensors() = *sensor;
    options.max_in_flight = 8;
    options.timeout = std::chrono::seconds(10);
    client = std::make_unique<client::RobotClient>(options);
    client->onAck([this](const v1::Ack& ack, std::chrono::nanoseconds) {
      std::lock_guard lock(mutex);
      // Logged before this session began ⇔ a duplicate: nothing is stored or applied twice.
      if (ack.duplicate() != (ack.seq() <= last_durable)) {
        problems.push_back("seq " + std::to_string(ack.seq()) + " acked with duplicate=" +
                           (ack.duplicate() ? "true" : "false") + ", last durable seq " + std::to_string(last_durable));
      }
      acked.insert(ack.seq());
      ++(ack.duplicate() ? duplicate_acks : fresh_acks);
    });
    client->onError([this](const v1::Error& e) {
      std::lock_guard lock(mutex);
      problems.push_back("Error " + e.code() + " for seq " + std::to_string(e.seq()) + ": " + e.message());
    });
    last_durable = client->connect().last_durable_seq();
  }

  /// Resends every message of earlier sessions that was not acknowledged, and
  /// `old_acked` acknowledged ones, with their own seq; waits for the acks.
  void resend(std::mt19937_64& rng, int old_acked) {
    std::vector<uint64_t> seqs;
    {
      std::lock_guard lock(mutex);
      for (uint64_t seq = 1; seq <= highest_sent; ++seq) {
        if (!acked.contains(seq)) seqs.push_back(seq);
      }
      for (int i = 0; i < old_acked && !acked.empty(); ++i) {
        seqs.push_back(*std::next(acked.begin(), static_cast<long>(rng() % acked.size())));
      }
    }
    for (const uint64_t seq : seqs) {
      v1::RobotMessage m = message(seq);
      m.set_seq(seq);
      client->resend(m);
    }
    EXPECT_TRUE(client->waitAllAcked(std::chrono::seconds(30))) << robot_id << ": resent messages not acked";
  }

  /// New messages until the server dies or the cycle's share is sent.
  void streamUntilKilled() {
    try {
      for (size_t n = 0; n < max_new_per_cycle; ++n) {
        const uint64_t seq = client->send(message(highest_sent + 1));
        ASSERT_EQ(seq, highest_sent + 1);
        highest_sent = seq;
        if (pace.count() > 0) std::this_thread::sleep_for(pace);
      }
      client->waitAllAcked(std::chrono::seconds(30));
    } catch (const client::ClientError&) {
      // Killed under us: what was in flight is resent next cycle.
    }
  }
};

/// Every cloud of `tracks` with seq in [1, in_map] is in the map once, those
/// in (in_map, highest_sent] are not; the scan map took `scans` scans.
void expectMapHolds(client::HttpClient& http, std::vector<Track*> cloud_tracks,
                    const std::vector<uint64_t>& in_map, uint64_t scans, const std::string& when) {
  SCOPED_TRACE(when);
  std::vector<Eigen::Vector3d> probes;
  std::vector<bool> expect_in;
  for (size_t r = 0; r < cloud_tracks.size(); ++r) {
    for (uint64_t seq = 1; seq <= cloud_tracks[r]->highest_sent; ++seq) {
      for (const Eigen::Vector3d& p : columnEndpoints((seq - 1) * cloud_tracks.size() + r)) {
        probes.push_back(p);
        expect_in.push_back(seq <= in_map[r]);
      }
    }
  }
  if (!probes.empty()) {
    const v1::OccupancyBatchResponse served = batchQuery(http, kCloudMap, probes);
    ASSERT_EQ(static_cast<size_t>(served.states_size()), probes.size());
    size_t wrong = 0;
    for (size_t i = 0; i < probes.size(); ++i) {
      const int i32 = static_cast<int>(i);
      const bool ok = expect_in[i] ? served.states(i32) == v1::OCCUPIED &&
                                         std::abs(served.probabilities(i32) - oneHitProbability()) < 1e-6
                                   : served.states(i32) == v1::UNKNOWN;
      if (!ok && wrong++ < 5) {
        ADD_FAILURE() << "endpoint " << probes[i].transpose() << " expected " << (expect_in[i] ? "hit once" : "unknown")
                      << ", served state " << served.states(i32) << " p " << served.probabilities(i32);
      }
    }
    EXPECT_EQ(wrong, 0u) << "of " << probes.size() << " endpoints";
  }
  if (scans > 0) {
    EXPECT_EQ(getJson(http, std::string("/v1/maps/") + kScanMap + "/layers")["scans"].get<uint64_t>(), scans);
  }
}

uint64_t faultSeed() {
  if (const char* text = std::getenv("RMAP_FAULT_SEED")) return std::strtoull(text, nullptr, 10);
  return std::random_device{}();
}

TEST(FaultCycles, Kill9AtRandomMomentsLosesNothingAcknowledgedAndAppliesNothingTwice) {
  const uint64_t seed = faultSeed();
  std::cout << "[ seed ] RMAP_FAULT_SEED=" << seed << "\n";
  RecordProperty("seed", std::to_string(seed));
  SCOPED_TRACE("RMAP_FAULT_SEED=" + std::to_string(seed));
  std::mt19937_64 rng(seed);
  TempDir dir("rmap-cycles");
  const auto data = dir.path() / "data";

  // The 2D robot's scans, made once in order (its odometry runs on), resent as they were.
  sim::BuildingOptions building;
  building.max_furniture_per_room = 1;
  const sim::VoxelWorld world = sim::makeBuilding(building, 3);
  client::Laser2dRobot walker = buildingWalker(world, 200);
  std::vector<v1::RobotMessage> scans;
  const auto scan = [&](uint64_t seq) {
    while (scans.size() < seq) {
      v1::RobotMessage m;
      *m.mutable_scan() = walker.next().scan;
      m.mutable_scan()->set_stamp_ns(static_cast<int64_t>(scans.size() + 1) * 100'000'000);
      scans.push_back(std::move(m));
    }
    return scans[seq - 1];
  };

  Track clouds_a, clouds_b, scanner;
  std::vector<Track*> cloud_tracks{&clouds_a, &clouds_b};
  for (size_t r = 0; r < cloud_tracks.size(); ++r) {
    cloud_tracks[r]->robot_id = "cloud-bot-" + std::to_string(r);
    cloud_tracks[r]->map = kCloudMap;
    cloud_tracks[r]->message = [r, n = cloud_tracks.size()](uint64_t seq) {
      return columnCloud((seq - 1) * n + r, static_cast<int64_t>(seq) * 100'000'000);
    };
    // Paced so that sending outlasts the longest delay before the kill.
    cloud_tracks[r]->max_new_per_cycle = 600;
    cloud_tracks[r]->pace = std::chrono::milliseconds(2);
  }
  scanner.robot_id = "scan-bot";
  scanner.map = kScanMap;
  scanner.message = scan;
  scanner.sensor = walker.sensor();
  // Every start replays the whole 2D SLAM: a few scans per cycle keep that short.
  scanner.max_new_per_cycle = 8;
  scanner.pace = std::chrono::milliseconds(40);
  std::vector<Track*> tracks{&clouds_a, &clouds_b, &scanner};

  std::vector<uint64_t> logged(tracks.size(), 0);  // D per robot, from the copy after the last kill
  uint64_t total_logged = 0;
  uint64_t lost = 0;  // acknowledged, then not in the log after a kill
  uint64_t in_flight_logged = 0, in_flight_unlogged = 0;
  for (int cycle = 0; cycle < kCycles; ++cycle) {
    SCOPED_TRACE("cycle " + std::to_string(cycle));
    RmapdProcess rmapd(data, kFaultConfig);
    client::HttpClient http(rmapd.httpUrl());
    // Recovery: the map holds what the log holds, no more.
    expectMapHolds(http, cloud_tracks, {logged[0], logged[1]}, logged[2], "after restart");
    EXPECT_EQ(metricValue(http.get("/metrics").body, "rmap_messages_durable_total"),
              static_cast<double>(total_logged));

    // Reconnect and resend: what was logged is acked as a duplicate, the rest is stored now.
    for (size_t t = 0; t < tracks.size(); ++t) {
      tracks[t]->connect(rmapd.wsUrl());
      EXPECT_EQ(tracks[t]->last_durable, logged[t]) << tracks[t]->robot_id;
      tracks[t]->resend(rng, 2);
    }
    expectMapHolds(http, cloud_tracks, {clouds_a.highest_sent, clouds_b.highest_sent}, scanner.highest_sent,
                   "after resending");

    // Ingest, and a kill -9 at a random moment of it.
    std::vector<std::thread> senders;
    for (Track* track : tracks) senders.emplace_back([track] { track->streamUntilKilled(); });
    const auto delay = std::chrono::milliseconds(50 + rng() % 1000);  // the cloud robots send for >= 1.2 s
    std::this_thread::sleep_for(delay);
    rmapd.kill9();
    for (std::thread& s : senders) s.join();
    for (Track* track : tracks) track->client.reset();

    const StoreContents copy = readStoreCopy(data, dir.path() / "copy");
    ASSERT_EQ(copy.integrity, "ok");
    total_logged = 0;
    for (size_t t = 0; t < tracks.size(); ++t) {
      Track& track = *tracks[t];
      const auto it = copy.seqs.find(track.robot_id);
      const std::vector<uint64_t> seqs = it == copy.seqs.end() ? std::vector<uint64_t>{} : it->second;
      logged[t] = seqs.size();
      total_logged += seqs.size();
      // One session commits in the order it sent, so a robot's log is 1..D, each once.
      for (size_t i = 0; i < seqs.size(); ++i) ASSERT_EQ(seqs[i], i + 1) << track.robot_id;
      ASSERT_LE(logged[t], track.highest_sent) << track.robot_id;
      std::lock_guard lock(track.mutex);
      for (const std::string& p : track.problems) ADD_FAILURE() << track.robot_id << ": " << p;
      track.problems.clear();
      const auto lost_here = static_cast<uint64_t>(std::distance(track.acked.upper_bound(logged[t]), track.acked.end()));
      EXPECT_EQ(lost_here, 0u) << track.robot_id << ": acknowledged messages missing from the log";
      lost += lost_here;
      // Sent but unacknowledged when rmapd died: logged ones come back as duplicates, the rest fresh.
      const auto acked_logged = static_cast<uint64_t>(std::distance(track.acked.begin(), track.acked.upper_bound(logged[t])));
      in_flight_logged += logged[t] - acked_logged;
      in_flight_unlogged += track.highest_sent - logged[t];
    }
    std::cout << "[ cycle " << cycle << " ] killed after " << delay.count() << " ms; logged";
    for (size_t t = 0; t < tracks.size(); ++t) std::cout << " " << tracks[t]->robot_id << " " << logged[t];
    std::cout << "\n";
  }

  // A last start after the last kill: everything acknowledged is back, the rest is resent, then a clean stop.
  RmapdProcess rmapd(data, kFaultConfig);
  client::HttpClient http(rmapd.httpUrl());
  expectMapHolds(http, cloud_tracks, {logged[0], logged[1]}, logged[2], "after the last restart");
  for (size_t t = 0; t < tracks.size(); ++t) {
    tracks[t]->connect(rmapd.wsUrl());
    tracks[t]->resend(rng, 0);
    tracks[t]->client.reset();
  }
  expectMapHolds(http, cloud_tracks, {clouds_a.highest_sent, clouds_b.highest_sent}, scanner.highest_sent,
                 "after the last resend");
  uint64_t fresh = 0, duplicates = 0, acked = 0;
  for (Track* track : tracks) {
    fresh += track->fresh_acks;
    duplicates += track->duplicate_acks;
    acked += track->acked.size();
  }
  EXPECT_EQ(rmapd.terminate(), 0);
  std::cout << "[ summary ] " << kCycles << " kill -9 cycles, " << acked << " messages acked (" << logged[0] + logged[1]
            << " clouds, " << logged[2] << " scans logged), " << fresh << " fresh acks, " << duplicates
            << " duplicate acks; unacknowledged at the kills: " << in_flight_logged << " logged (acked as duplicates once resent), "
            << in_flight_unlogged << " not (stored once resent); " << lost << " acknowledged messages lost\n";
}

}  // namespace
}  // namespace rmap::testing
