#include "app/viewer_hub.h"

#include <algorithm>

namespace rmap::app {

nlohmann::json poseJson(const RobotPose& pose) {
  const Eigen::Vector3d p = pose.pose.translation();
  const Eigen::Quaterniond q(pose.pose.linear());
  return {{"robot_id", pose.robot_id}, {"map", pose.map},         {"seq", pose.seq},
          {"stamp_ns", pose.stamp_ns}, {"position", {p.x(), p.y(), p.z()}},
          {"orientation", {q.w(), q.x(), q.y(), q.z()}}};
}

ViewerSession::ViewerSession(ViewerHub& hub, std::string map) : hub_(hub), map_(std::move(map)) {}

void ViewerSession::onOpen(std::shared_ptr<net::WsConnection> connection) {
  connection_ = std::move(connection);
  connection_->send(nlohmann::json{{"type", "hello"}, {"map", map_}}.dump(), false);
  hub_.add(shared_from_this());
}

void ViewerSession::onMessage(std::string, bool) {
  // The stream is server → viewer; viewers have nothing to say yet.
}

void ViewerSession::onClose() { hub_.remove(this); }

ViewerHub::ViewerHub(Metrics& metrics, size_t max_queue_bytes) : metrics_(metrics), max_queue_bytes_(max_queue_bytes) {}

void ViewerHub::add(const std::shared_ptr<ViewerSession>& viewer) {
  std::lock_guard lock(mutex_);
  viewers_.push_back(viewer);
}

void ViewerHub::remove(const ViewerSession* viewer) {
  std::lock_guard lock(mutex_);
  std::erase_if(viewers_, [&](const auto& v) { return v.get() == viewer; });
}

size_t ViewerHub::viewers() const {
  std::lock_guard lock(mutex_);
  return viewers_.size();
}

ViewerBacklog ViewerHub::backlog() const {
  std::lock_guard lock(mutex_);
  ViewerBacklog backlog;
  for (const auto& viewer : viewers_) {
    backlog.skipping += viewer->needs_resync_;
    backlog.queued_bytes += viewer->connection_->queuedBytes();
  }
  return backlog;
}

void ViewerHub::publishPose(const RobotPose& pose) {
  std::lock_guard lock(mutex_);
  latest_poses_[pose.robot_id] = pose;
}

void ViewerHub::publishEvent(const std::string& map, const nlohmann::json& event) {
  std::lock_guard lock(mutex_);
  broadcast(map, event.dump());
}

void ViewerHub::broadcast(const std::string& map, const std::string& frame) {
  for (const auto& viewer : viewers_) {
    if (!viewer->map_.empty() && viewer->map_ != map) continue;
    net::WsConnection& connection = *viewer->connection_;
    if (viewer->needs_resync_) {
      // Skip until the backlog is gone, then let the viewer re-read the tileset instead of replaying history.
      if (connection.queuedBytes() > max_queue_bytes_ / 2) {
        metrics_.viewer_frames_dropped.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
      viewer->needs_resync_ = !connection.send(nlohmann::json{{"type", "resync"}}.dump(), false);
      if (viewer->needs_resync_) continue;
    }
    if (connection.queuedBytes() + frame.size() > max_queue_bytes_ || !connection.send(frame, false)) {
      viewer->needs_resync_ = true;
      metrics_.viewer_frames_dropped.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    metrics_.viewer_frames_sent.fetch_add(1, std::memory_order_relaxed);
  }
}

void ViewerHub::tick(const std::vector<std::shared_ptr<MapWorker>>& maps) {
  for (const auto& worker : maps) {
    const std::vector<TileVersion> changed = worker->tiles().update(worker->map());
    if (changed.empty()) continue;
    nlohmann::json tiles = nlohmann::json::array();
    for (const TileVersion& t : changed) tiles.push_back({t.key.level, t.key.x, t.key.y, t.key.z, t.version});
    const nlohmann::json frame{{"type", "tiles"},
                               {"map", worker->name()},
                               {"map_version", worker->tiles().mapVersion()},
                               {"tiles", std::move(tiles)}};
    std::lock_guard lock(mutex_);
    broadcast(worker->name(), frame.dump());
  }
  std::lock_guard lock(mutex_);
  std::map<std::string, nlohmann::json> by_map;
  for (const auto& [robot, pose] : latest_poses_) {
    nlohmann::json& frame = by_map[pose.map];
    if (frame.is_null()) frame = {{"type", "poses"}, {"map", pose.map}, {"poses", nlohmann::json::array()}};
    frame["poses"].push_back(poseJson(pose));
  }
  latest_poses_.clear();
  for (const auto& [map, frame] : by_map) broadcast(map, frame.dump());
}

}  // namespace rmap::app
