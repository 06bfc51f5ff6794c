#include "app/mapping_service.h"

#include <spdlog/spdlog.h>

#include <nlohmann/json.hpp>

#include "app/robot_session.h"
#include "map3d/map_file.h"

#ifndef RMAP_VERSION
#define RMAP_VERSION "dev"
#endif

namespace rmap::app {

namespace {

int64_t nowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace

const char* MappingService::version() { return RMAP_VERSION; }

MappingService::MappingService(Config config)
    : config_(std::move(config)), viewers_(metrics_, config_.limits.viewer_send_queue_bytes) {
  store_ = store::Store::open(config_.data_dir);
  metrics_.messages_durable = store_->messageCount();
  const auto start = std::chrono::steady_clock::now();
  for (const store::MapRecord& record : store_->maps()) {
    auto worker = makeWorker(record, true);
    maps_.emplace(record.name, worker);
  }
  if (!maps_.empty()) {
    spdlog::info("recovered {} map(s), {} message(s) replayed in {:.2f} s", maps_.size(),
                 metrics_.messages_recovered.load(),
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  for (auto& [name, worker] : maps_) worker->start();
  committer_ = std::make_unique<store::GroupCommitter>(*store_);
  tick_thread_ = std::thread([this] { tickLoop(); });
}

MappingService::~MappingService() {
  {
    std::lock_guard lock(tick_mutex_);
    stopping_ = true;
  }
  tick_wake_.notify_all();
  if (tick_thread_.joinable()) tick_thread_.join();
  committer_.reset();  // completions post to the workers, so drain it first
  std::lock_guard lock(maps_mutex_);
  maps_.clear();
}

std::shared_ptr<MapWorker> MappingService::makeWorker(const store::MapRecord& record, bool recover) {
  std::unique_ptr<map3d::CuboidMap> map;
  int64_t applied_id = 0;
  if (recover) {
    if (std::optional<store::Snapshot> snapshot = store_->snapshot(record.name)) {
      try {
        map = map3d::decodeMap(snapshot->blob);
        applied_id = snapshot->last_message_id;
      } catch (const std::exception& e) {
        // The log holds every message, so a bad snapshot only costs a longer replay.
        spdlog::warn("map {}: snapshot unreadable ({}), replaying the whole log", record.name, e.what());
      }
    }
  }
  if (!map) {
    map = std::make_unique<map3d::CuboidMap>(record.resolution_m, config_.maps.occupancy, config_.maps.fusion);
  }
  auto worker = std::make_shared<MapWorker>(record.name, std::move(map), applied_id, config_, *store_, metrics_,
                                            [this](const RobotPose& pose) { onPose(pose); });
  if (recover) {
    store_->forEachMessage(record.name, applied_id, [&](const store::StoredMessage& stored) {
      v1::RobotMessage message;
      if (!message.ParseFromString(stored.record.payload)) {
        spdlog::error("map {}: logged message {} does not parse; skipped", record.name, stored.id);
        return true;
      }
      try {
        worker->applyNow(stored.id, message, stored.record.robot_id);
      } catch (const std::exception& e) {
        spdlog::error("map {}: logged message {} could not be applied: {}", record.name, stored.id, e.what());
      }
      metrics_.messages_recovered.fetch_add(1, std::memory_order_relaxed);
      return true;
    });
  }
  worker->tiles().update(worker->map());
  return worker;
}

std::shared_ptr<MapWorker> MappingService::openMap(const std::string& name, double resolution_m) {
  std::lock_guard lock(maps_mutex_);
  if (const auto it = maps_.find(name); it != maps_.end()) return it->second;
  nlohmann::json params{{"fusion_tolerance_log_odds", config_.maps.fusion.tolerance_log_odds},
                        {"max_range_m", config_.maps.occupancy.max_range_m}};
  const store::MapRecord record = store_->ensureMap(
      {name, resolution_m > 0.0 ? resolution_m : config_.maps.resolution_m, params.dump(), nowNs()});
  auto worker = makeWorker(record, false);
  worker->start();
  maps_.emplace(name, worker);
  spdlog::info("map {} created, resolution {} m", name, record.resolution_m);
  return worker;
}

std::shared_ptr<MapWorker> MappingService::findMap(const std::string& name) const {
  std::lock_guard lock(maps_mutex_);
  const auto it = maps_.find(name);
  return it == maps_.end() ? nullptr : it->second;
}

std::vector<std::shared_ptr<MapWorker>> MappingService::maps() const {
  std::lock_guard lock(maps_mutex_);
  std::vector<std::shared_ptr<MapWorker>> out;
  for (const auto& [name, worker] : maps_) out.push_back(worker);
  return out;
}

uint64_t MappingService::robotConnected(const std::string& robot_id, const std::string& map,
                                        const std::string& sensors_json,
                                        const std::shared_ptr<RobotSession>& session) {
  std::shared_ptr<RobotSession> previous;
  {
    std::lock_guard lock(robots_mutex_);
    std::weak_ptr<RobotSession>& slot = sessions_[robot_id];
    previous = slot.lock();
    slot = session;
  }
  if (previous && previous != session) {
    previous->closeWithError("replaced", "robot " + robot_id + " connected again on another stream");
  }
  store::RobotRecord record;
  record.robot_id = robot_id;
  record.map = map;
  record.sensors_json = sensors_json;
  record.first_seen_ns = record.last_seen_ns = nowNs();
  store_->upsertRobot(record);
  return store_->lastSeq(robot_id);
}

void MappingService::robotDisconnected(const std::string& robot_id, const RobotSession* session) {
  std::lock_guard lock(robots_mutex_);
  const auto it = sessions_.find(robot_id);
  if (it == sessions_.end()) return;
  const auto current = it->second.lock();
  if (!current || current.get() == session) sessions_.erase(it);
}

size_t MappingService::robotConnections() const {
  std::lock_guard lock(robots_mutex_);
  return sessions_.size();
}

std::vector<RobotStatus> MappingService::robots() const {
  std::vector<RobotStatus> out;
  for (const store::RobotRecord& record : store_->robots()) {
    RobotStatus status{record, false, std::nullopt};
    std::lock_guard lock(robots_mutex_);
    status.connected = sessions_.count(record.robot_id) > 0;
    if (const auto it = last_poses_.find(record.robot_id); it != last_poses_.end()) status.last_pose = it->second;
    out.push_back(std::move(status));
  }
  return out;
}

std::optional<RobotStatus> MappingService::robot(const std::string& robot_id) const {
  std::optional<store::RobotRecord> record = store_->robot(robot_id);
  if (!record) return std::nullopt;
  RobotStatus status{*record, false, std::nullopt};
  std::lock_guard lock(robots_mutex_);
  status.connected = sessions_.count(robot_id) > 0;
  if (const auto it = last_poses_.find(robot_id); it != last_poses_.end()) status.last_pose = it->second;
  return status;
}

void MappingService::onPose(const RobotPose& pose) {
  {
    std::lock_guard lock(robots_mutex_);
    last_poses_[pose.robot_id] = pose;
  }
  viewers_.publishPose(pose);
}

void MappingService::tickLoop() {
  std::unique_lock lock(tick_mutex_);
  while (!tick_wake_.wait_for(lock, std::chrono::milliseconds(config_.viewer_tick_ms), [&] { return stopping_; })) {
    lock.unlock();
    try {
      viewers_.tick(maps());
    } catch (const std::exception& e) {
      spdlog::error("viewer tick: {}", e.what());
    }
    lock.lock();
  }
}

MetricsGauges MappingService::gauges() const {
  MetricsGauges g;
  g.robot_connections = robotConnections();
  g.viewer_connections = viewers_.viewers();
  g.commit_queue_messages = committer_->queuedMessages();
  g.commit_queue_bytes = committer_->queuedBytes();
  for (const auto& worker : maps()) {
    g.maps += 1;
    g.map_queue_messages += worker->queueDepth();
    const map3d::MapStats stats = worker->map().stats();
    g.cuboids += stats.cuboids;
    g.map_memory_bytes += stats.memory_bytes;
  }
  return g;
}

}  // namespace rmap::app
