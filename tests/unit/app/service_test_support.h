#pragma once
/// @file service_test_support.h
/// What the tests of the units around MappingService share: a service over a
/// fresh data directory, robot messages and WebSocket connections that
/// record what a robot's or a viewer's session sends.

#include <gtest/gtest.h>

#include <boost/beast/http/field.hpp>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "../store/temp_dir.h"
#include "app/mapping_service.h"
#include "net/service.h"
#include "rmap/v1/robot_stream.pb.h"

namespace rmap::app::testing {

/// A response header's value, empty when the response has none.
template <class Field>
std::string header(const net::Response& response, Field field) {
  const auto it = response.find(field);
  return it == response.end() ? std::string() : std::string(it->value());
}

inline Config configIn(const std::filesystem::path& data_dir) {
  Config config;
  config.data_dir = data_dir;
  return config;
}

/// A cloud in the map frame: rays from `origin` to each point (m).
inline v1::RobotMessage cloudMessage(uint64_t seq, const Eigen::Vector3d& origin,
                                     const std::vector<Eigen::Vector3f>& points) {
  v1::RobotMessage m;
  m.set_seq(seq);
  v1::PointCloud& cloud = *m.mutable_cloud();
  cloud.set_frame(v1::PointCloud::MAP);
  // Modulo 2^53 before scaling: some tests send seqs near 2^63, and the stamp must not overflow.
  cloud.set_stamp_ns(static_cast<int64_t>(seq % (uint64_t{1} << 53)) * 1000);
  cloud.mutable_sensor_pose()->mutable_position_m()->set_x(origin.x());
  cloud.mutable_sensor_pose()->mutable_position_m()->set_y(origin.y());
  cloud.mutable_sensor_pose()->mutable_position_m()->set_z(origin.z());
  for (const Eigen::Vector3f& p : points) {
    for (int a = 0; a < 3; ++a) cloud.add_xyz_m(p[a]);
  }
  return m;
}

/// A small cloud near the origin: one ray along x, ending in cell (10, 0, 0) at 0.1 m.
inline v1::RobotMessage smallCloud(uint64_t seq) {
  return cloudMessage(seq, {0.05, 0.05, 0.05}, {{1.05f, 0.05f, 0.05f}});
}

/// Records the ServerMessages a robot session sends; thread-safe (replies come from the
/// committer and the map workers).
class RecordingConnection : public net::WsConnection {
 public:
  bool send(std::string data, bool binary) override {
    EXPECT_TRUE(binary);
    v1::ServerMessage message;
    EXPECT_TRUE(message.ParseFromString(data));
    std::lock_guard lock(mutex_);
    sent_.push_back(std::move(message));
    changed_.notify_all();
    return true;
  }
  size_t queuedBytes() const override { return 0; }
  void pauseReading(bool) override {}
  void close(uint16_t, const std::string&) override {}
  const net::Peer& peer() const override { return peer_; }

  std::vector<v1::ServerMessage> sent() const {
    std::lock_guard lock(mutex_);
    return sent_;
  }
  /// What was sent once there are at least `count` messages, or after 10 s.
  std::vector<v1::ServerMessage> waitFor(size_t count) const {
    std::unique_lock lock(mutex_);
    changed_.wait_for(lock, std::chrono::seconds(10), [&] { return sent_.size() >= count; });
    return sent_;
  }

 private:
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  std::vector<v1::ServerMessage> sent_;
  net::Peer peer_{"127.0.0.1", 40000, true};
};

/// A viewer's WebSocket: records the JSON frames sent; queuedBytes and
/// whether send succeeds are set by the test. Not thread-safe.
class ViewerConnection : public net::WsConnection {
 public:
  bool send(std::string data, bool binary) override {
    EXPECT_FALSE(binary);
    if (!accept) return false;
    frames.push_back(nlohmann::json::parse(data));
    return true;
  }
  size_t queuedBytes() const override { return queued; }
  void pauseReading(bool) override {}
  void close(uint16_t, const std::string&) override {}
  const net::Peer& peer() const override { return peer_; }

  std::vector<nlohmann::json> frames;
  size_t queued = 0;
  bool accept = true;

 private:
  net::Peer peer_{"127.0.0.1", 1, true};
};

}  // namespace rmap::app::testing
