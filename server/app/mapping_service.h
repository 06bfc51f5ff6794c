#pragma once
/// @file mapping_service.h
/// The heart of rmapd, free of HTTP: the store and its group committer, the
/// named maps and their workers, connected robots, the viewer hub, metrics.
/// At construction it rebuilds every map from its snapshot plus the message
/// log after it, so everything acknowledged before a crash is back.

#include <atomic>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "app/config.h"
#include "app/map_worker.h"
#include "app/memory_bound.h"
#include "app/metrics.h"
#include "app/place_recognizer.h"
#include "app/viewer_hub.h"
#include "store/group_commit.h"
#include "store/store.h"

namespace rmap::app {

class RobotSession;

/// A connected or known robot as the API reports it.
struct RobotStatus {
  store::RobotRecord record;  ///< last_seen_ns includes the open stream's latest message
  bool connected = false;
  std::optional<RobotPose> last_pose;
};

class MappingService {
 public:
  /// Opens the store under config.data_dir and recovers the maps.
  /// @param recognizers  place recognition per map and kind of frame (nullptr from the
  ///                     factory: that kind is off); by default bowRecognizers(config.loop_closure,
  ///                     config.slam2d.options.loop_closure)
  /// @throws store::StoreError, std::runtime_error with a clear message
  explicit MappingService(Config config, std::optional<RecognizerFactory> recognizers = std::nullopt);
  /// Stops the tick thread, drains the committer and the workers (final snapshots).
  ~MappingService();
  MappingService(const MappingService&) = delete;
  MappingService& operator=(const MappingService&) = delete;

  static const char* version();
  /// Identifies this start of the server over the life of the store: larger
  /// than that of every earlier start (it is the id of a durable start event).
  /// Map and tile versions restart with each start, so (epoch, version) is
  /// what never repeats, e.g. in ETags.
  int64_t epoch() const { return epoch_; }
  const Config& config() const { return config_; }
  Metrics& metrics() { return metrics_; }
  store::Store& store() { return *store_; }
  store::GroupCommitter& committer() { return *committer_; }
  ViewerHub& viewers() { return viewers_; }
  /// Stores a loop closure found on a map (once: replays find it again) and pushes it to the
  /// map's viewers; a withdrawn one is marked in the store and pushed as withdrawn (once). Every
  /// map's place recognition and 2D SLAM deliver their closures here (on their feed's thread).
  void recordLoopClosure(const LoopClosure& closure);
  /// limits.max_memory_bytes against this process's resident memory.
  MemoryBound& memoryBound() { return memory_bound_; }

  /// The map of that name, created (and stored) with `resolution_m` (0 = the
  /// configured default) when missing.
  std::shared_ptr<MapWorker> openMap(const std::string& name, double resolution_m);
  std::shared_ptr<MapWorker> findMap(const std::string& name) const;
  std::vector<std::shared_ptr<MapWorker>> maps() const;

  /// Hands a durable message to its map's worker; `applied` runs on the
  /// worker once the message is in the map.
  void apply(MapWorker& map, int64_t log_id, std::shared_ptr<const v1::RobotMessage> message,
             std::string robot_id, std::function<void()> applied);
  /// Runs `fn` once the logged message `log_id` is in its map: at once when it
  /// already is (applied, or recovered at start), else on the worker thread
  /// right after it is applied. For acks of duplicates, which must not
  /// overtake the first copy.
  void whenApplied(int64_t log_id, std::function<void()> fn);

  /// Records the 2D lasers of a robot's Hello for its messages with seq >
  /// `after_seq` (durably, before the Welcome: a replay gives scans the same
  /// sensors). @throws store::StoreError
  void declareLasers(const std::string& robot_id, const std::string& map, uint64_t after_seq,
                     std::vector<Laser2dSetup> lasers);

  /// Registers a robot's stream (an older stream of the same robot is closed)
  /// and returns its highest durable sequence number.
  uint64_t robotConnected(const std::string& robot_id, const std::string& map, const std::string& sensors_json,
                          const std::shared_ptr<RobotSession>& session);
  void robotDisconnected(const std::string& robot_id, const RobotSession* session);
  std::vector<RobotStatus> robots() const;
  std::optional<RobotStatus> robot(const std::string& robot_id) const;
  size_t robotConnections() const;
  /// Writes the latest message time of connected robots to the store, where
  /// it changed (also done every second by the tick thread and at disconnect).
  void persistLastSeen();

  /// Source of the open-connection gauge (e.g. net::Server::connections);
  /// set it before serving. Without one the gauge reads 0.
  void setConnectionCounter(std::function<size_t()> counter) { connection_counter_ = std::move(counter); }
  MetricsGauges gauges() const;

 private:
  /// A robot's open stream and its robot record as last written to the store.
  struct Connected {
    std::weak_ptr<RobotSession> session;
    store::RobotRecord record;
  };

  std::shared_ptr<MapWorker> makeWorker(const store::MapRecord& record, bool recover);

  void appliedDone(int64_t log_id);
  RobotStatus status(const store::RobotRecord& record) const;  ///< needs robots_mutex_
  void onPose(const RobotPose& pose);
  void sendEstimate(const std::string& robot_id, const v1::PoseEstimate& estimate);
  /// Reads the robots' declared lasers and the maps' first SLAM and place recognition inputs
  /// from the store's events.
  void loadSlam2dEvents();
  void tickLoop();

  Config config_;
  Metrics metrics_;
  MemoryBound memory_bound_;
  std::unique_ptr<store::Store> store_;
  int64_t epoch_ = 0;
  ViewerHub viewers_;
  Calibrations calibrations_;
  RobotSensors sensors_;
  std::mutex declare_mutex_;                        ///< one declareLasers at a time: check, store, record
  std::map<std::string, int64_t> slam_first_input_;  ///< per map, from the store's events at start
  std::map<std::string, int64_t> loop_first_input_;  ///< per map, from the store's events at start
  RecognizerFactory recognizers_;
  mutable std::mutex maps_mutex_;
  std::map<std::string, std::shared_ptr<MapWorker>> maps_;
  std::mutex applying_mutex_;
  /// Log ids handed to workers and not yet applied, with what waits for them.
  std::unordered_map<int64_t, std::vector<std::function<void()>>> applying_;
  mutable std::mutex robots_mutex_;
  std::map<std::string, Connected> sessions_;
  std::map<std::string, RobotPose> last_poses_;
  std::function<size_t()> connection_counter_;
  std::unique_ptr<store::GroupCommitter> committer_;
  std::mutex tick_mutex_;
  std::condition_variable tick_wake_;
  bool stopping_ = false;
  std::thread tick_thread_;
};

}  // namespace rmap::app
