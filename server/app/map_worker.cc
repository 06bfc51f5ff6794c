#include "app/map_worker.h"

#include <spdlog/spdlog.h>

#include <map>

#include "app/ingest.h"
#include "map3d/map_file.h"

namespace rmap::app {

namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kPoseFlushPeriod = std::chrono::milliseconds(500);
constexpr size_t kPoseFlushCount = 512;

store::TrajectoryPose toTrajectoryPose(const RobotPose& p) {
  store::TrajectoryPose t;
  t.stamp_ns = p.stamp_ns;
  t.seq = p.seq;
  const Eigen::Vector3d position = p.pose.translation();
  const Eigen::Quaterniond q(p.pose.linear());
  for (int a = 0; a < 3; ++a) t.position_m[a] = position[a];
  t.orientation_wxyz[0] = q.w();
  t.orientation_wxyz[1] = q.x();
  t.orientation_wxyz[2] = q.y();
  t.orientation_wxyz[3] = q.z();
  return t;
}

}  // namespace

MapWorker::MapWorker(std::string name, std::unique_ptr<map3d::CuboidMap> map, int64_t applied_id,
                     const Config& config, store::Store& store, Metrics& metrics, PoseSink pose_sink)
    : name_(std::move(name)),
      map_(std::move(map)),
      config_(config),
      store_(store),
      metrics_(metrics),
      pose_sink_(std::move(pose_sink)),
      applied_id_(applied_id),
      snapshot_id_(applied_id),
      last_snapshot_(Clock::now()),
      last_pose_flush_(Clock::now()) {}

MapWorker::~MapWorker() { stop(); }

void MapWorker::stop() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  try {
    flushTrajectories();
    writeSnapshot();
  } catch (const std::exception& e) {
    spdlog::error("map {}: final snapshot failed: {}", name_, e.what());
  }
}

void MapWorker::start() { thread_ = std::thread([this] { run(); }); }

void MapWorker::post(int64_t log_id, std::shared_ptr<const v1::RobotMessage> message, std::string robot_id,
                     std::function<void()> applied) {
  {
    std::lock_guard lock(mutex_);
    queue_.push_back({log_id, std::move(message), std::move(robot_id), std::move(applied)});
  }
  wake_.notify_one();
}

size_t MapWorker::queueDepth() const {
  std::lock_guard lock(mutex_);
  return queue_.size();
}

int64_t MapWorker::appliedId() const { return applied_id_.load(); }

void MapWorker::applyNow(int64_t log_id, const v1::RobotMessage& message, const std::string& robot_id) {
  apply(log_id, message, robot_id);
}

void MapWorker::run() {
  std::deque<Item> batch;
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      // Wake at least every flush period so poses and snapshots go out when ingest pauses.
      wake_.wait_for(lock, kPoseFlushPeriod, [&] { return stopping_ || !queue_.empty(); });
      if (queue_.empty() && stopping_) return;
      batch.swap(queue_);
    }
    for (Item& item : batch) {
      const auto start = Clock::now();
      try {
        apply(item.log_id, *item.message, item.robot_id);
      } catch (const std::exception& e) {
        // A checked message should not fail; log it and keep the map going (it stays in the log).
        spdlog::error("map {}: message {} of {} could not be applied: {}", name_, item.message->seq(),
                      item.robot_id, e.what());
      }
      metrics_.apply_latency.observe(std::chrono::duration<double>(Clock::now() - start).count());
      if (item.applied) item.applied();
    }
    batch.clear();
    try {
      if (!pending_poses_.empty() &&
          (pending_poses_.size() >= kPoseFlushCount || Clock::now() - last_pose_flush_ >= kPoseFlushPeriod)) {
        flushTrajectories();
      }
      if (applied_id_.load() > snapshot_id_ &&
          Clock::now() - last_snapshot_ >= std::chrono::duration<double>(config_.snapshot_interval_s)) {
        flushTrajectories();  // poses of messages inside the snapshot must not depend on the replay
        writeSnapshot();
      }
    } catch (const std::exception& e) {
      spdlog::error("map {}: {}", name_, e.what());
    }
  }
}

void MapWorker::apply(int64_t log_id, const v1::RobotMessage& message, const std::string& robot_id) {
  if (message.body_case() == v1::RobotMessage::kCloud) {
    const v1::PointCloud& cloud = message.cloud();
    const CloudInMap in_map = cloudInMap(cloud);
    map3d::InsertOptions options;
    options.threads = config_.maps.insert_threads;
    // Points outside the addressable range are dropped rather than refusing a whole durable message.
    options.invalid_points = map3d::InvalidPoints::kSkip;
    const map3d::ScanStats stats = map_->insertScan(sensorOrigin(cloud), in_map.points_m, options);
    metrics_.points_integrated.fetch_add(stats.points - stats.rejected_points, std::memory_order_relaxed);
    const RobotPose pose{robot_id, name_, message.seq(), cloud.stamp_ns(), in_map.sensor_pose};
    pending_poses_.emplace_back(robot_id, toTrajectoryPose(pose));
    if (pose_sink_) pose_sink_(pose);
  } else if (message.body_case() == v1::RobotMessage::kImage && message.image().has_camera_pose()) {
    const RobotPose pose{robot_id, name_, message.seq(), message.image().stamp_ns(),
                         toIsometry(message.image().camera_pose())};
    if (pose_sink_) pose_sink_(pose);
  }
  // 2D scans, images and odometry are durable and ordered here; SLAM and loop closure consume them in later stages.
  applied_id_.store(log_id);
}

void MapWorker::flushTrajectories() {
  if (pending_poses_.empty()) return;
  std::map<std::string, std::vector<store::TrajectoryPose>> by_robot;
  for (auto& [robot, pose] : pending_poses_) by_robot[robot].push_back(pose);
  pending_poses_.clear();
  last_pose_flush_ = Clock::now();
  for (const auto& [robot, poses] : by_robot) store_.appendTrajectory(robot, poses);
}

void MapWorker::writeSnapshot() {
  const int64_t applied = applied_id_.load();
  last_snapshot_ = Clock::now();
  if (applied <= snapshot_id_) return;
  store_.putSnapshot({name_, applied, map3d::encodeMap(*map_)});
  snapshot_id_ = applied;
  metrics_.snapshots_written.fetch_add(1, std::memory_order_relaxed);
}

}  // namespace rmap::app
