// kill -9 in the middle of a stream: after a restart every acknowledged
// message is in the map, which equals the map built offline from exactly the
// durable messages.
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <set>
#include <thread>

#include "api_helpers.h"
#include "client/robot_client.h"
#include "map3d/cuboid_map.h"
#include "rmapd_process.h"
#include "scene_clouds.h"

namespace rmap::testing {
namespace {

client::RobotClientOptions robotOptions(const std::string& url) {
  client::RobotClientOptions options;
  options.server_url = url;
  options.hello.set_robot_id("crash-bot");
  options.hello.set_map("crash");
  options.max_in_flight = 8;
  return options;
}

TEST(CrashRecovery, EveryAcknowledgedMessageSurvivesKill9) {
  TempDir dir("rmap-crash");
  const client::SimScene scene = client::makeSimScene(3);
  const std::vector<v1::RobotMessage> clouds = sceneClouds(scene, 60, 5);

  std::set<uint64_t> acked;
  std::mutex acked_mutex;
  {
    RmapdProcess rmapd(dir.path() / "data");
    client::RobotClient robot(robotOptions(rmapd.wsUrl()));
    robot.onAck([&](const v1::Ack& ack, std::chrono::nanoseconds) {
      std::lock_guard lock(acked_mutex);
      acked.insert(ack.seq());
    });
    ASSERT_EQ(robot.connect().last_durable_seq(), 0u);
    std::atomic<bool> stop{false};
    std::thread sender([&] {
      try {
        for (const v1::RobotMessage& m : clouds) {
          if (stop) break;
          robot.send(m);
        }
      } catch (const client::ClientError&) {
        // The server died under us: expected.
      }
    });
    // Crash once a good part is acknowledged while more is in flight.
    while (true) {
      {
        std::lock_guard lock(acked_mutex);
        if (acked.size() >= 20) break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    rmapd.kill9();
    stop = true;
    sender.join();
  }
  std::set<uint64_t> acked_before_crash;
  {
    std::lock_guard lock(acked_mutex);
    acked_before_crash = acked;
  }
  ASSERT_GE(acked_before_crash.size(), 20u);
  const uint64_t max_acked = *acked_before_crash.rbegin();

  RmapdProcess rmapd(dir.path() / "data");
  client::RobotClient robot(robotOptions(rmapd.wsUrl()));
  const uint64_t durable = robot.connect().last_durable_seq();
  EXPECT_GE(durable, max_acked) << "an acknowledged message was lost";
  ASSERT_LE(durable, clouds.size());

  client::HttpClient http(rmapd.httpUrl());
  const std::string metrics = http.get("/metrics").body;
  EXPECT_EQ(metricValue(metrics, "rmap_messages_durable_total"), static_cast<double>(durable));
  EXPECT_EQ(metricValue(metrics, "rmap_messages_recovered_total"), static_cast<double>(durable));

  // Offline: the same messages in the same order into a fresh map.
  map3d::CuboidMap offline(getJson(http, "/v1/maps/crash")["resolution_m"].get<double>());
  std::vector<Eigen::Vector3d> probes;
  for (uint64_t seq = 1; seq <= durable; ++seq) {
    const v1::PointCloud& cloud = clouds[seq - 1].cloud();
    std::vector<Eigen::Vector3f> points(static_cast<size_t>(cloud.xyz_m_size() / 3));
    for (size_t i = 0; i < points.size(); ++i) {
      points[i] = {cloud.xyz_m(3 * i), cloud.xyz_m(3 * i + 1), cloud.xyz_m(3 * i + 2)};
      // Endpoints and the middles of their rays probe occupied and free cells.
      if (i % 40 == 0) {
        const Eigen::Vector3d origin(cloud.sensor_pose().position_m().x(), cloud.sensor_pose().position_m().y(),
                                     cloud.sensor_pose().position_m().z());
        probes.push_back(points[i].cast<double>());
        probes.push_back(0.5 * (origin + points[i].cast<double>()));
      }
    }
    const v1::Vector3& o = cloud.sensor_pose().position_m();
    map3d::InsertOptions options;
    options.invalid_points = map3d::InvalidPoints::kSkip;
    offline.insertScan(Eigen::Vector3f(o.x(), o.y(), o.z()), points, options);
  }
  const v1::OccupancyBatchResponse served = batchQuery(http, "crash", probes);
  size_t occupied = 0;
  for (size_t i = 0; i < probes.size(); ++i) {
    const map3d::CellQuery q = offline.query(probes[i]);
    const int expected = q.state == map3d::CellState::kOccupied ? v1::OCCUPIED
                         : q.state == map3d::CellState::kFree   ? v1::FREE
                                                                : v1::UNKNOWN;
    ASSERT_EQ(served.states(static_cast<int>(i)), expected) << "probe " << i << " at " << probes[i].transpose();
    ASSERT_NEAR(served.probabilities(static_cast<int>(i)), q.probability, 1e-6);
    occupied += expected == v1::OCCUPIED;
  }
  EXPECT_GT(occupied, probes.size() / 4);
  EXPECT_EQ(getJson(http, "/v1/maps/crash")["cuboids"].get<uint64_t>(), offline.stats().cuboids);

  // The robot carries on after the last durable message.
  for (uint64_t seq = durable + 1; seq <= clouds.size(); ++seq) EXPECT_EQ(robot.send(clouds[seq - 1]), seq);
  EXPECT_TRUE(robot.waitAllAcked(std::chrono::seconds(60)));
  EXPECT_EQ(getJson(http, "/v1/robots/crash-bot")["last_seq"].get<uint64_t>(), clouds.size());
}

}  // namespace
}  // namespace rmap::testing
