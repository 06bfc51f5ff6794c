#pragma once
/// @file viewer_hub.h
/// The viewer stream `/v1/stream/viewer?map=`: JSON text frames pushing
/// tile-changed notices, robot poses and events of one map (or of all maps
/// when `map` is empty). Robots never wait for viewers: a viewer whose send
/// queue is full misses frames and is told to resynchronise (re-read
/// tileset.json) once it has caught up.

#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "app/map_worker.h"
#include "app/metrics.h"
#include "app/tiles.h"
#include "net/service.h"

namespace rmap::app {

class ViewerHub;

class ViewerSession : public net::WsHandler, public std::enable_shared_from_this<ViewerSession> {
 public:
  ViewerSession(ViewerHub& hub, std::string map);
  void onOpen(std::shared_ptr<net::WsConnection> connection) override;
  void onMessage(std::string data, bool binary) override;
  void onClose() override;

  const std::string& map() const { return map_; }
  /// Sends a frame unless the viewer is too far behind (then it owes a resync).
  void push(const std::string& frame);

 private:
  friend class ViewerHub;
  ViewerHub& hub_;
  std::string map_;
  std::shared_ptr<net::WsConnection> connection_;
  bool needs_resync_ = false;  ///< guarded by the hub's mutex
};

/// How far behind the viewers are, at one moment.
struct ViewerBacklog {
  size_t skipping = 0;      ///< viewers whose frames are skipped until they catch up
  size_t queued_bytes = 0;  ///< queued to all viewers (each at most the hub's bound)
};

class ViewerHub {
 public:
  ViewerHub(Metrics& metrics, size_t max_queue_bytes);

  void add(const std::shared_ptr<ViewerSession>& viewer);
  void remove(const ViewerSession* viewer);
  size_t viewers() const;
  ViewerBacklog backlog() const;

  /// Keeps the latest pose of each robot for the next tick.
  void publishPose(const RobotPose& pose);
  /// Pushes an event of a map at once (e.g. a loop closure).
  void publishEvent(const std::string& map, const nlohmann::json& event);
  /// Pushes tile changes of the maps and the poses gathered since the last tick.
  void tick(const std::vector<std::shared_ptr<MapWorker>>& maps);

 private:
  void broadcast(const std::string& map, const std::string& frame);

  Metrics& metrics_;
  size_t max_queue_bytes_;
  mutable std::mutex mutex_;
  std::vector<std::shared_ptr<ViewerSession>> viewers_;
  std::map<std::string, RobotPose> latest_poses_;  ///< by robot id
};

/// JSON of a pose for the API and the viewer stream.
nlohmann::json poseJson(const RobotPose& pose);

}  // namespace rmap::app
