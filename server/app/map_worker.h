#pragma once
/// @file map_worker.h
/// One named map and the thread that applies durable robot messages to it in
/// log order, so a replay of the log rebuilds the same map. Also writes the
/// map's snapshots and the trajectory poses the messages carry. Laser scans
/// go through the map's 2D SLAM; each estimate goes back to its robot, becomes
/// its pose and puts the scan into the 3D map as a planar cloud.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "app/config.h"
#include "app/loop_closure_feed.h"
#include "app/metrics.h"
#include "app/robot_sensors.h"
#include "app/slam2d_layer.h"
#include "app/tiles.h"
#include "map3d/cuboid_map.h"
#include "map3d/octomap_interop.h"
#include "rmap/v1/robot_stream.pb.h"
#include "store/store.h"

namespace rmap::app {

/// Event kind marking the first message that fed a map's 2D SLAM ({"message_id": id}):
/// recovery replays the SLAM from there, also below the 3D snapshot.
inline constexpr const char* kSlam2dInputEvent = "slam2d_input";
/// The same for the first frame that fed a map's place recognition.
inline constexpr const char* kLoopInputEvent = "loop_input";
/// Frames waiting for place recognition at most, per map (see LoopClosureFeed).
inline constexpr size_t kLoopQueueFrames = 16;

/// A robot pose a message placed in the map.
struct RobotPose {
  std::string robot_id;
  std::string map;
  uint64_t seq = 0;
  int64_t stamp_ns = 0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

class MapWorker {
 public:
  using PoseSink = std::function<void(const RobotPose&)>;
  /// Sends a 2D SLAM estimate to the robot's open stream, if any.
  using EstimateSink = std::function<void(const std::string& robot_id, const v1::PoseEstimate&)>;

  /// What the 2D SLAM of a map needs from the service.
  struct Slam2dInputs {
    const Calibrations& calibrations;
    const RobotSensors& sensors;
    EstimateSink estimate_sink;
    /// Log id of the first message that fed this map's SLAM (kSlam2dInputEvent), 0 when none yet.
    int64_t first_input_id = 0;
  };

  /// What loop closure of a map needs from the service.
  struct LoopInputs {
    const RecognizerFactory& recognizers;
    LoopClosureSink sink;
    /// Log id of the first message that fed this map's place recognition (kLoopInputEvent), 0 when none yet.
    int64_t first_input_id = 0;
  };

  /// @param map            the map (from a snapshot or new)
  /// @param applied_id     log id already in `map` (the snapshot's), 0 for a new map
  MapWorker(std::string name, std::unique_ptr<map3d::CuboidMap> map, int64_t applied_id, const Config& config,
            store::Store& store, Metrics& metrics, PoseSink pose_sink, Slam2dInputs slam2d, LoopInputs loop);
  /// stop().
  ~MapWorker();
  MapWorker(const MapWorker&) = delete;
  MapWorker& operator=(const MapWorker&) = delete;

  /// Applies a message synchronously on the caller's thread (recovery, before start()).
  /// A message at or below the snapshot's id only feeds the 2D SLAM, which has no snapshot.
  void applyNow(int64_t log_id, const v1::RobotMessage& message, const std::string& robot_id);
  /// Where recovery starts reading the log: after the snapshot, or earlier for the 2D SLAM
  /// and place recognition, which have no snapshot.
  int64_t replayFromId() const;
  /// Whether a logged message of this kind (RobotMessage body field) at or below the
  /// snapshot's id still has to be replayed (it feeds the 2D SLAM or place recognition).
  bool replaysBelowSnapshot(int32_t kind) const;
  /// Starts the apply thread.
  void start();
  /// Applies what is queued, joins the thread and writes a final snapshot; later
  /// calls do nothing. The owner calls it while the store and metrics live: a
  /// session may hold the worker longer, and its last reference may even be
  /// dropped on the worker thread.
  void stop();
  /// Queues a durable message; `applied` runs on the worker thread afterwards.
  void post(int64_t log_id, std::shared_ptr<const v1::RobotMessage> message, std::string robot_id,
            std::function<void()> applied);

  /// Replaces the 3D map's content by `blocks` (e.g. an imported OctoMap, same resolution) on
  /// the worker thread, between two messages, and returns once that is durable: a snapshot of
  /// the new content is stored first, so a failure leaves the map as it was; then the live map
  /// is rewritten (readers may see it part-way for that long). Blocks the import does not fill
  /// are emptied. Messages applied later go on top; the 2D layer and trajectories are kept.
  /// @param replace  when false and the map holds known cells, nothing changes
  /// @return false when the map was not empty and `replace` is false
  /// @throws store::StoreError when the snapshot could not be stored (nothing changed)
  bool importBlocks(const map3d::MapBlocks& blocks, bool replace);

  const std::string& name() const { return name_; }
  const map3d::CuboidMap& map() const { return *map_; }
  const Slam2dLayer& slam2d() const { return slam2d_; }
  TileIndex& tiles() { return tiles_; }
  size_t queueDepth() const;
  /// Frames waiting for place recognition.
  size_t loopQueueDepth() const;
  /// Waits until every frame queued so far went through place recognition (tests, benchmarks).
  void drainLoopClosures();
  int64_t appliedId() const;

 private:
  /// A durable message to apply, or (no message) a task that only runs `applied` in its turn.
  struct Item {
    int64_t log_id;
    std::shared_ptr<const v1::RobotMessage> message;
    std::string robot_id;
    std::function<void()> applied;
  };
  void run();
  void apply(int64_t log_id, const v1::RobotMessage& message, const std::string& robot_id, bool live);
  /// @param in_map3d  the 3D map, trajectory and robot poses hold this message already (snapshot)
  void applyScan(int64_t log_id, const v1::RobotMessage& message, const std::string& robot_id, bool in_map3d,
                 bool live);
  void applyCloud(const v1::RobotMessage& message, const std::string& robot_id);
  /// Geometry closures to the loop feed, which stores and pushes them; accepted ones first:
  /// a closure can be accepted and withdrawn with one scan.
  void postClosures(const std::vector<slam2d::LoopClosure2d>& accepted,
                    const std::vector<slam2d::LoopClosure2d>& withdrawn);
  /// After the pose graph moved poses: the moved scans' trajectory poses and robots' poses follow,
  /// and the 3D map's planar rows where they drew are rendered again from the corrected 2D grid.
  /// @param in_map3d  the scan that triggered it is below the 3D snapshot (only the bookkeeping moves)
  void applyCorrection(bool in_map3d);
  /// Rewrites the 3D cells of rows `rows` (z cells) over `region_m` from the 2D grid.
  void rewritePlanarRows(const Eigen::AlignedBox2d& region_m, const std::set<int32_t>& rows);
  void noteSlamInput(int64_t log_id);
  /// Whether a frame of `kind` at `place` is far enough from its robot's last one of that kind
  /// (then it becomes the last one).
  bool newPlace(FrameKind kind, const LoopPlace& place);
  /// Queue frames for place recognition when that kind is on and the place is new; live
  /// frames are dropped rather than waited for when recognition is behind.
  void feedImage(int64_t log_id, const v1::RobotMessage& message, const std::string& robot_id, bool live);
  /// The intensity panorama of a cloud with intensities.
  void feedCloud(int64_t log_id, const v1::RobotMessage& message, const std::string& robot_id, bool live);
  /// The reflectivity patch around a 2D-laser robot.
  void feedPatch(int64_t log_id, const std::string& robot_id, int64_t stamp_ns, const slam2d::Pose2& base_pose,
                 bool live);
  void noteLoopInput(int64_t log_id);
  void publishPose(const RobotPose& pose);
  void flushTrajectories();
  void writeSnapshot();
  /// importBlocks on the worker thread.
  bool replaceContent(const map3d::MapBlocks& blocks, bool replace);

  std::string name_;
  std::unique_ptr<map3d::CuboidMap> map_;
  const Config& config_;
  store::Store& store_;
  Metrics& metrics_;
  PoseSink pose_sink_;
  TileIndex tiles_;
  Slam2dLayer slam2d_;
  const RobotSensors& sensors_;
  EstimateSink estimate_sink_;
  int64_t slam_first_input_id_;
  int64_t loop_first_input_id_;
  std::map<std::string, RobotPose> last_poses_;  ///< worker thread only: places of frames without their own pose
  /// A scan as it went into the 3D map, to find what a correction moved.
  struct PlanarScan {
    int64_t stamp_ns = 0;
    uint64_t seq = 0;
    slam2d::Pose2 base_pose;  ///< robot base where its planar cloud was drawn (or last re-rendered)
    slam2d::Pose2 mount;      ///< laser in the robot base
    double height_m = 0.0;    ///< laser height of the planar cloud
    float reach_m = 0.0f;     ///< longest beam drawn
    bool in_map3d = false;    ///< the cloud was drawn (it had beams and an addressable origin)
  };
  std::map<std::string, std::vector<PlanarScan>> planar_scans_;  ///< worker thread only, per robot, scan order
  /// Worker thread only: each robot's last frame of each kind put to place recognition.
  std::map<std::pair<FrameKind, std::string>, LoopPlace> last_frames_;
  /// Declared after what its callbacks use; stopped in stop().
  std::unique_ptr<LoopClosureFeed> loop_feed_;
  const int64_t restored_id_;  ///< log id of the snapshot the 3D map was restored from

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Item> queue_;
  bool stopping_ = false;
  std::atomic<int64_t> applied_id_{0};
  int64_t snapshot_id_ = 0;
  std::chrono::steady_clock::time_point last_snapshot_;
  std::vector<std::pair<std::string, store::TrajectoryPose>> pending_poses_;
  std::chrono::steady_clock::time_point last_pose_flush_;
  /// Messages applied since the hot blocks were last fused, and when the latest was.
  bool unfused_changes_ = false;
  std::chrono::steady_clock::time_point last_apply_;
  std::thread thread_;
};

}  // namespace rmap::app
