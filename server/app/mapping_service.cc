#include "app/mapping_service.h"

#include <spdlog/spdlog.h>

#include <nlohmann/json.hpp>

#include "app/bow_recognizer.h"
#include "app/robot_session.h"
#include "app/wall_clock.h"
#include "map3d/map_file.h"

#ifndef RMAP_VERSION
#define RMAP_VERSION "dev"
#endif

namespace rmap::map3d {

NLOHMANN_JSON_SERIALIZE_ENUM(SensorModel, {{SensorModel::kBeam, "beam"}, {SensorModel::kEndpoint, "endpoint"}})
NLOHMANN_JSON_SERIALIZE_ENUM(FreeSpaceTracing, {{FreeSpaceTracing::kOctomapExact, "octomap_exact"},
                                                {FreeSpaceTracing::kStopAtFreed, "stop_at_freed"}})

}  // namespace rmap::map3d

namespace rmap::app {

namespace {

/// How often the tick thread writes robots' latest message times to the store.
constexpr auto kLastSeenPersistPeriod = std::chrono::seconds(1);

/// Calls fn(key, field) for every parameter that shapes a map's content, under its key in the
/// map's stored params_json: one list for writing and reading them.
template <typename Occupancy, typename Fusion, typename Fn>
void forEachMapParam(Occupancy& o, Fusion& f, Fn&& fn) {
  fn("hit_log_odds", o.hit_log_odds);
  fn("miss_log_odds", o.miss_log_odds);
  fn("clamp_min_log_odds", o.clamp_min_log_odds);
  fn("clamp_max_log_odds", o.clamp_max_log_odds);
  fn("occupied_threshold_log_odds", o.occupied_threshold_log_odds);
  fn("max_range_m", o.max_range_m);
  fn("sensor_model", o.sensor_model);
  fn("free_space_tracing", o.free_space_tracing);
  fn("stop_after_freed_cells", o.stop_after_freed_cells);
  fn("fusion_tolerance_log_odds", f.tolerance_log_odds);
  fn("fuse_after_scans", f.fuse_after_scans);
}

nlohmann::json mapParamsJson(const map3d::OccupancyParams& occupancy, const map3d::FusionParams& fusion) {
  nlohmann::json out = nlohmann::json::object();
  forEachMapParam(occupancy, fusion, [&](const char* key, const auto& value) { out[key] = value; });
  return out;
}

/// Reads a map's stored parameters over `occupancy` and `fusion`.
/// @return the keys absent from `params_json` (maps stored by older versions), which keep their value
/// @throws std::runtime_error naming the map when the stored parameters do not parse
std::vector<std::string> readMapParams(const store::MapRecord& record, map3d::OccupancyParams& occupancy,
                                       map3d::FusionParams& fusion) {
  std::vector<std::string> missing;
  try {
    const nlohmann::json stored = nlohmann::json::parse(record.params_json);
    forEachMapParam(occupancy, fusion, [&](const char* key, auto& value) {
      if (stored.contains(key)) {
        stored.at(key).get_to(value);
      } else {
        missing.emplace_back(key);
      }
    });
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error("map " + record.name + ": stored parameters are unreadable: " + e.what());
  }
  return missing;
}

}  // namespace

const char* MappingService::version() { return RMAP_VERSION; }

MappingService::MappingService(Config config, std::optional<RecognizerFactory> recognizers)
    : config_(std::move(config)),
      memory_bound_(config_.limits.max_memory_bytes),
      viewers_(metrics_, config_.limits.viewer_send_queue_bytes),
      calibrations_(loadCalibrations(config_.slam2d)),
      recognizers_(recognizers ? std::move(*recognizers) : bowRecognizers(config_.loop_closure, config_.slam2d.options.loop_closure)) {
  store_ = store::Store::open(config_.data_dir);
  loadSlam2dEvents();
  // Event ids are never reused, so the id of this start's event exceeds every earlier epoch.
  epoch_ = store_->appendEvent({0, "", "rmapd_start", nowNs(), nlohmann::json{{"version", version()}}.dump()});
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
  if (memory_bound_.maxBytes() != 0) {
    const double mib = 1 << 20;
    spdlog::info("memory bound {:.4g} MiB, resident now {:.0f} MiB", memory_bound_.maxBytes() / mib,
                 residentBytes() / mib);
    if (memory_bound_.exceeded()) {
      spdlog::warn("{}: robot data is refused until resident memory falls below it", memory_bound_.describe());
    }
  }
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
  // Stopped here, not by their destructors: callbacks still queued hold sessions, which hold workers.
  for (auto& [name, worker] : maps_) worker->stop();
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
    // Replaying the log must rebuild the map the clients saw: with the parameters it was created with.
    map3d::OccupancyParams occupancy = config_.maps.occupancy;
    map3d::FusionParams fusion = config_.maps.fusion;
    const std::vector<std::string> missing = readMapParams(record, occupancy, fusion);
    if (!missing.empty()) {
      spdlog::warn("map {}: stored without {}; the config's values are used", record.name,
                   nlohmann::json(missing).dump());
    }
    map = std::make_unique<map3d::CuboidMap>(record.resolution_m, occupancy, fusion);
  }
  if (recover) {
    const nlohmann::json kept = mapParamsJson(map->occupancyParams(), map->fusionParams());
    const nlohmann::json configured = mapParamsJson(config_.maps.occupancy, config_.maps.fusion);
    if (kept != configured) {
      spdlog::warn("map {} keeps the parameters it was created with {}; the config's {} apply to new maps only",
                   record.name, kept.dump(), configured.dump());
    }
  }
  const auto first_input = slam_first_input_.find(record.name);
  MapWorker::Slam2dInputs slam2d{
      calibrations_, sensors_,
      [this](const std::string& robot_id, const v1::PoseEstimate& estimate) { sendEstimate(robot_id, estimate); },
      first_input == slam_first_input_.end() ? 0 : first_input->second};
  const auto loop_first = loop_first_input_.find(record.name);
  MapWorker::LoopInputs loop{recognizers_, [this](const LoopClosure& closure) { recordLoopClosure(closure); },
                             loop_first == loop_first_input_.end() ? 0 : loop_first->second};
  auto worker =
      std::make_shared<MapWorker>(record.name, std::move(map), applied_id, config_, *store_, metrics_,
                                  [this](const RobotPose& pose) { onPose(pose); }, std::move(slam2d), std::move(loop));
  if (recover) {
    store_->forEachMessage(record.name, worker->replayFromId(), [&](const store::StoredMessage& stored) {
      // Below the snapshot only the inputs of the 2D SLAM and place recognition are replayed.
      if (stored.id <= applied_id && !worker->replaysBelowSnapshot(stored.record.kind)) return true;
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
  const store::MapRecord record =
      store_->ensureMap({name, resolution_m > 0.0 ? resolution_m : config_.maps.resolution_m,
                         mapParamsJson(config_.maps.occupancy, config_.maps.fusion).dump(), nowNs()});
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

void MappingService::apply(MapWorker& map, int64_t log_id, std::shared_ptr<const v1::RobotMessage> message,
                           std::string robot_id, std::function<void()> applied) {
  {
    std::lock_guard lock(applying_mutex_);
    applying_.try_emplace(log_id);
  }
  map.post(log_id, std::move(message), std::move(robot_id), [this, log_id, applied = std::move(applied)] {
    if (applied) applied();
    appliedDone(log_id);
  });
}

void MappingService::whenApplied(int64_t log_id, std::function<void()> fn) {
  {
    // Completions come in log order, so the first copy was handed to apply() before a duplicate
    // of it asks here: a log id not being applied is in its map already.
    std::lock_guard lock(applying_mutex_);
    if (const auto it = applying_.find(log_id); it != applying_.end()) {
      it->second.push_back(std::move(fn));
      return;
    }
  }
  fn();
}

void MappingService::appliedDone(int64_t log_id) {
  std::vector<std::function<void()>> waiting;
  {
    std::lock_guard lock(applying_mutex_);
    auto node = applying_.extract(log_id);
    if (!node.empty()) waiting = std::move(node.mapped());
  }
  for (const auto& fn : waiting) fn();
}

uint64_t MappingService::robotConnected(const std::string& robot_id, const std::string& map,
                                        const std::string& sensors_json,
                                        const std::shared_ptr<RobotSession>& session) {
  store::RobotRecord record;
  record.robot_id = robot_id;
  record.map = map;
  record.sensors_json = sensors_json;
  record.first_seen_ns = record.last_seen_ns = nowNs();
  std::shared_ptr<RobotSession> previous;
  {
    std::lock_guard lock(robots_mutex_);
    Connected& slot = sessions_[robot_id];
    previous = slot.session.lock();
    slot = {session, record};
  }
  if (previous && previous != session) {
    previous->closeWithError("replaced", "robot " + robot_id + " connected again on another stream");
  }
  store_->upsertRobot(record);
  return store_->lastSeq(robot_id);
}

void MappingService::robotDisconnected(const std::string& robot_id, const RobotSession* session) {
  std::optional<store::RobotRecord> last;
  {
    std::lock_guard lock(robots_mutex_);
    const auto it = sessions_.find(robot_id);
    if (it == sessions_.end()) return;
    const auto current = it->second.session.lock();
    if (current && current.get() != session) return;  // replaced: the newer stream owns the record
    if (current && current->lastSeenNs() > it->second.record.last_seen_ns) {
      last = it->second.record;
      last->last_seen_ns = current->lastSeenNs();
    }
    sessions_.erase(it);
  }
  if (last) store_->upsertRobot(*last);
}

void MappingService::persistLastSeen() {
  std::vector<store::RobotRecord> changed;
  {
    std::lock_guard lock(robots_mutex_);
    for (auto& [robot_id, connected] : sessions_) {
      const auto session = connected.session.lock();
      if (!session || session->lastSeenNs() <= connected.record.last_seen_ns) continue;
      connected.record.last_seen_ns = session->lastSeenNs();
      changed.push_back(connected.record);
    }
  }
  for (const store::RobotRecord& record : changed) store_->upsertRobot(record);
}

size_t MappingService::robotConnections() const {
  std::lock_guard lock(robots_mutex_);
  return sessions_.size();
}

RobotStatus MappingService::status(const store::RobotRecord& record) const {
  RobotStatus status{record, false, std::nullopt};
  if (const auto it = sessions_.find(record.robot_id); it != sessions_.end()) {
    status.connected = true;
    // The store's value trails the stream by up to kLastSeenPersistPeriod.
    if (const auto session = it->second.session.lock()) {
      status.record.last_seen_ns = std::max(status.record.last_seen_ns, session->lastSeenNs());
    }
  }
  if (const auto it = last_poses_.find(record.robot_id); it != last_poses_.end()) status.last_pose = it->second;
  return status;
}

std::vector<RobotStatus> MappingService::robots() const {
  const std::vector<store::RobotRecord> records = store_->robots();
  std::vector<RobotStatus> out;
  std::lock_guard lock(robots_mutex_);
  for (const store::RobotRecord& record : records) out.push_back(status(record));
  return out;
}

std::optional<RobotStatus> MappingService::robot(const std::string& robot_id) const {
  const std::optional<store::RobotRecord> record = store_->robot(robot_id);
  if (!record) return std::nullopt;
  std::lock_guard lock(robots_mutex_);
  return status(*record);
}

void MappingService::loadSlam2dEvents() {
  constexpr size_t kPage = 1000;
  for (int64_t cursor = 0;;) {
    const std::vector<store::EventRecord> events = store_->events("", cursor, kPage);
    for (const store::EventRecord& e : events) {
      cursor = e.id;
      try {
        if (e.kind == kRobotSensorsEvent) {
          sensors_.addJson(e.json);
        } else if (e.kind == kSlam2dInputEvent || e.kind == kLoopInputEvent) {
          const int64_t id = nlohmann::json::parse(e.json).at("message_id").get<int64_t>();
          auto& first = e.kind == kSlam2dInputEvent ? slam_first_input_ : loop_first_input_;
          auto [it, inserted] = first.try_emplace(e.map, id);
          if (!inserted) it->second = std::min(it->second, id);
        }
      } catch (const std::exception& ex) {
        throw std::runtime_error("event " + std::to_string(e.id) + " (" + e.kind + ") is unreadable: " + ex.what());
      }
    }
    if (events.size() < kPage) break;
  }
}

void MappingService::declareLasers(const std::string& robot_id, const std::string& map, uint64_t after_seq,
                                   std::vector<Laser2dSetup> lasers) {
  std::lock_guard lock(declare_mutex_);
  if (!sensors_.isNew(robot_id, after_seq, lasers)) return;
  store_->appendEvent({0, map, kRobotSensorsEvent, nowNs(), lasersJson(robot_id, after_seq, lasers)});
  sensors_.add(robot_id, after_seq, std::move(lasers));
}

void MappingService::sendEstimate(const std::string& robot_id, const v1::PoseEstimate& estimate) {
  std::shared_ptr<RobotSession> session;
  {
    std::lock_guard lock(robots_mutex_);
    if (const auto it = sessions_.find(robot_id); it != sessions_.end()) session = it->second.session.lock();
  }
  if (session && session->sendPoseEstimate(estimate)) {
    metrics_.pose_estimates_sent.fetch_add(1, std::memory_order_relaxed);
  }
}

void MappingService::onPose(const RobotPose& pose) {
  {
    std::lock_guard lock(robots_mutex_);
    last_poses_[pose.robot_id] = pose;
  }
  viewers_.publishPose(pose);
}

void MappingService::recordLoopClosure(const LoopClosure& closure) {
  if (closure.withdrawn) {
    const std::optional<store::LoopClosureRecord> withdrawn = store_->withdrawLoopClosure(toRecord(closure, 0), nowNs());
    if (!withdrawn) return;  // withdrawn before (a replay of the log), or never stored
    metrics_.loop_closures_withdrawn.fetch_add(1, std::memory_order_relaxed);
    spdlog::info("map {}: {} loop closure {} withdrawn: a later pose graph optimisation dropped it", closure.map,
                 toString(closure.source), withdrawn->id);
    nlohmann::json frame = loopClosureJson(*withdrawn);
    frame["type"] = "loop_closure_withdrawn";
    viewers_.publishEvent(closure.map, frame);
    return;
  }
  store::LoopClosureRecord record = toRecord(closure, nowNs());
  const std::optional<int64_t> id = store_->appendLoopClosure(record);
  if (!id) return;  // found again by a replay of the log
  record.id = *id;
  metrics_.loop_closures[static_cast<size_t>(closure.source)].fetch_add(1, std::memory_order_relaxed);
  spdlog::info("map {}: {} loop closure {} between {} at {} ns and {} at {} ns, score {:.3f}", closure.map,
               toString(closure.source), *id, closure.query.robot_id, closure.query.stamp_ns,
               closure.match.robot_id, closure.match.stamp_ns, closure.score);
  nlohmann::json frame = loopClosureJson(record);
  frame["type"] = "loop_closure";
  viewers_.publishEvent(closure.map, frame);
}

void MappingService::tickLoop() {
  auto last_seen_persisted = std::chrono::steady_clock::now();
  std::unique_lock lock(tick_mutex_);
  while (!tick_wake_.wait_for(lock, std::chrono::milliseconds(config_.viewer_tick_ms), [&] { return stopping_; })) {
    lock.unlock();
    try {
      const auto tick_start = std::chrono::steady_clock::now();
      viewers_.tick(maps());
      metrics_.viewer_tick_latency.observe(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - tick_start).count());
    } catch (const std::exception& e) {
      spdlog::error("viewer tick: {}", e.what());
    }
    if (std::chrono::steady_clock::now() - last_seen_persisted >= kLastSeenPersistPeriod) {
      last_seen_persisted = std::chrono::steady_clock::now();
      try {
        persistLastSeen();
      } catch (const std::exception& e) {
        spdlog::error("robots' last seen times not stored: {}", e.what());
      }
    }
    lock.lock();
  }
}

MetricsGauges MappingService::gauges() const {
  MetricsGauges g;
  g.robot_connections = robotConnections();
  g.viewer_connections = viewers_.viewers();
  const ViewerBacklog backlog = viewers_.backlog();
  g.viewers_skipping = backlog.skipping;
  g.viewer_queue_bytes = backlog.queued_bytes;
  g.resident_memory_bytes = residentBytes();
  g.resident_memory_peak_bytes = peakResidentBytes();
  g.memory_bound_bytes = memory_bound_.maxBytes();
  if (connection_counter_) g.http_connections = connection_counter_();
  g.commit_queue_messages = committer_->queuedMessages();
  g.commit_queue_bytes = committer_->queuedBytes();
  for (const auto& worker : maps()) {
    g.maps += 1;
    g.map_queue_messages += worker->queueDepth();
    g.loop_queue_frames += worker->loopQueueDepth();
    const map3d::MapStats stats = worker->map().stats();
    g.cuboids += stats.cuboids;
    g.map_memory_bytes += stats.memory_bytes;
  }
  return g;
}

}  // namespace rmap::app
