#pragma once
/// @file mapping_service.h
/// The heart of rmapd, free of HTTP: the store and its group committer, the
/// named maps and their workers, connected robots, the viewer hub, metrics.
/// At construction it rebuilds every map from its snapshot plus the message
/// log after it, so everything acknowledged before a crash is back.

#include <atomic>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "app/config.h"
#include "app/map_worker.h"
#include "app/metrics.h"
#include "app/viewer_hub.h"
#include "store/group_commit.h"
#include "store/store.h"

namespace rmap::app {

class RobotSession;

/// A connected or known robot as the API reports it.
struct RobotStatus {
  store::RobotRecord record;
  bool connected = false;
  std::optional<RobotPose> last_pose;
};

class MappingService {
 public:
  /// Opens the store under config.data_dir and recovers the maps.
  /// @throws store::StoreError, std::runtime_error with a clear message
  explicit MappingService(Config config);
  /// Stops the tick thread, drains the committer and the workers (final snapshots).
  ~MappingService();
  MappingService(const MappingService&) = delete;
  MappingService& operator=(const MappingService&) = delete;

  static const char* version();
  const Config& config() const { return config_; }
  Metrics& metrics() { return metrics_; }
  store::Store& store() { return *store_; }
  store::GroupCommitter& committer() { return *committer_; }
  ViewerHub& viewers() { return viewers_; }

  /// The map of that name, created (and stored) with `resolution_m` (0 = the
  /// configured default) when missing.
  std::shared_ptr<MapWorker> openMap(const std::string& name, double resolution_m);
  std::shared_ptr<MapWorker> findMap(const std::string& name) const;
  std::vector<std::shared_ptr<MapWorker>> maps() const;

  /// Registers a robot's stream (an older stream of the same robot is closed)
  /// and returns its highest durable sequence number.
  uint64_t robotConnected(const std::string& robot_id, const std::string& map, const std::string& sensors_json,
                          const std::shared_ptr<RobotSession>& session);
  void robotDisconnected(const std::string& robot_id, const RobotSession* session);
  std::vector<RobotStatus> robots() const;
  std::optional<RobotStatus> robot(const std::string& robot_id) const;
  size_t robotConnections() const;

  MetricsGauges gauges() const;

 private:
  std::shared_ptr<MapWorker> makeWorker(const store::MapRecord& record, bool recover);
  void onPose(const RobotPose& pose);
  void tickLoop();

  Config config_;
  Metrics metrics_;
  std::unique_ptr<store::Store> store_;
  ViewerHub viewers_;
  mutable std::mutex maps_mutex_;
  std::map<std::string, std::shared_ptr<MapWorker>> maps_;
  mutable std::mutex robots_mutex_;
  std::map<std::string, std::weak_ptr<RobotSession>> sessions_;
  std::map<std::string, RobotPose> last_poses_;
  std::unique_ptr<store::GroupCommitter> committer_;
  std::mutex tick_mutex_;
  std::condition_variable tick_wake_;
  bool stopping_ = false;
  std::thread tick_thread_;
};

}  // namespace rmap::app
