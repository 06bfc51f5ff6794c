#include "app/map_worker.h"

#include <spdlog/spdlog.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <future>
#include <map>
#include <set>
#include <unordered_set>

#include "app/camera_frames.h"
#include "app/ingest.h"
#include "app/wall_clock.h"
#include "loop/panorama.h"
#include "loop/reflectivity_patch.h"
#include "map3d/map_file.h"

namespace rmap::app {

namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kPoseFlushPeriod = std::chrono::milliseconds(500);
constexpr size_t kPoseFlushCount = 512;
/// A map that received nothing for this long fuses its hot blocks: an idle map holds the
/// compact form a finished benchmark build and a recovered server hold (same cell states,
/// far fewer cuboids). Streams pause longer than this only between sessions.
constexpr auto kIdleFuseDelay = std::chrono::seconds(1);
/// Place recognition takes a robot's next frame of a kind once it moved or turned this much
/// since its last one (or, without poses, this much later): nearer frames show the same place,
/// and a lidar at 10 Hz would otherwise keep a core busy.
constexpr double kFrameSpacing_m = 0.5;
constexpr double kFrameSpacing_rad = 0.5;
constexpr int64_t kFrameSpacing_ns = 500'000'000;

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

/// Writes `blocks` into `map` a slice at a time: replaceBlocks holds every block it writes
/// expanded (16.9 KB) until it fuses them, so one call for a whole import would need that per block.
void replaceBlocksInSlices(map3d::CuboidMap& map, const map3d::MapBlocks& blocks) {
  constexpr size_t kSliceBlocks = 1024;
  for (size_t begin = 0; begin < blocks.size(); begin += kSliceBlocks) {
    const size_t end = std::min(blocks.size(), begin + kSliceBlocks);
    map.replaceBlocks(map3d::MapBlocks(blocks.begin() + static_cast<std::ptrdiff_t>(begin),
                                       blocks.begin() + static_cast<std::ptrdiff_t>(end)));
  }
}

}  // namespace

MapWorker::MapWorker(std::string name, std::unique_ptr<map3d::CuboidMap> map, int64_t applied_id,
                     const Config& config, store::Store& store, Metrics& metrics, PoseSink pose_sink,
                     Slam2dInputs slam2d, LoopInputs loop)
    : name_(std::move(name)),
      map_(std::move(map)),
      config_(config),
      store_(store),
      metrics_(metrics),
      pose_sink_(std::move(pose_sink)),

      slam2d_(config.slam2d.options, slam2d.calibrations, metrics),
      sensors_(slam2d.sensors),
      estimate_sink_(std::move(slam2d.estimate_sink)),
      slam_first_input_id_(slam2d.first_input_id),
      loop_first_input_id_(loop.first_input_id),
      loop_feed_(std::make_unique<LoopClosureFeed>(name_, loop.recognizers, std::move(loop.sink), metrics,
                                                   kLoopQueueFrames)),
      restored_id_(applied_id),
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
  loop_feed_->stop();  // after the worker: nothing queues frames any more
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

size_t MapWorker::loopQueueDepth() const { return loop_feed_->queued(); }

void MapWorker::drainLoopClosures() { loop_feed_->drain(); }

void MapWorker::applyNow(int64_t log_id, const v1::RobotMessage& message, const std::string& robot_id) {
  apply(log_id, message, robot_id, false);
}

int64_t MapWorker::replayFromId() const {
  int64_t from = restored_id_;
  for (const int64_t first : {slam_first_input_id_, loop_first_input_id_}) {
    if (first > 0) from = std::min(from, first - 1);
  }
  return from;
}

bool MapWorker::replaysBelowSnapshot(int32_t kind) const {
  switch (kind) {
    case v1::RobotMessage::kScan:
    case v1::RobotMessage::kOdometry: return true;
    case v1::RobotMessage::kImage: return loop_feed_->accepts(FrameKind::kCamera);
    case v1::RobotMessage::kCloud: return loop_feed_->accepts(FrameKind::kIntensityPanorama);
    default: return false;
  }
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
      if (!item.message) {
        item.applied();
        continue;
      }
      const auto start = Clock::now();
      try {
        apply(item.log_id, *item.message, item.robot_id, true);
      } catch (const std::exception& e) {
        // A checked message should not fail; log it and keep the map going (it stays in the log).
        spdlog::error("map {}: message {} of {} could not be applied: {}", name_, item.message->seq(),
                      item.robot_id, e.what());
      }
      metrics_.apply_latency.observe(std::chrono::duration<double>(Clock::now() - start).count());
      if (item.applied) item.applied();
    }
    if (!batch.empty()) {
      unfused_changes_ = true;
      last_apply_ = Clock::now();
    }
    batch.clear();
    try {
      if (unfused_changes_ && Clock::now() - last_apply_ >= kIdleFuseDelay) {
        map_->fuseAll(config_.maps.insert_threads);
        unfused_changes_ = false;
        // Ingest paused: no scan will test the closures waiting for a later optimisation for now.
        postClosures(slam2d_.confirmLoopClosures(), {});
      }
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

void MapWorker::apply(int64_t log_id, const v1::RobotMessage& message, const std::string& robot_id, bool live) {
  const bool in_map3d = log_id <= restored_id_;
  if (message.body_case() == v1::RobotMessage::kScan) {
    noteSlamInput(log_id);
    applyScan(log_id, message, robot_id, in_map3d, live);
  } else if (message.body_case() == v1::RobotMessage::kOdometry) {
    noteSlamInput(log_id);
    slam2d_.addOdometry(robot_id, message.odometry());
  } else if (message.body_case() == v1::RobotMessage::kImage) {
    feedImage(log_id, message, robot_id, live);
    if (!in_map3d && message.image().has_camera_pose()) {
      publishPose({robot_id, name_, message.seq(), message.image().stamp_ns(),
                   toIsometry(message.image().camera_pose())});
    }
  } else if (message.body_case() == v1::RobotMessage::kCloud) {
    feedCloud(log_id, message, robot_id, live);
    // Below the snapshot, recovery replays the inputs of the 2D SLAM and place recognition only.
    if (!in_map3d) applyCloud(message, robot_id);
  }
  if (log_id > applied_id_.load()) applied_id_.store(log_id);
}

void MapWorker::noteSlamInput(int64_t log_id) {
  if (slam_first_input_id_ > 0) return;
  // Stored before the message counts as applied, so every snapshot that holds it comes after the mark.
  store_.appendEvent({0, name_, kSlam2dInputEvent, nowNs(), nlohmann::json{{"message_id", log_id}}.dump()});
  slam_first_input_id_ = log_id;
}

void MapWorker::applyCloud(const v1::RobotMessage& message, const std::string& robot_id) {
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
  publishPose(pose);
}

void MapWorker::noteLoopInput(int64_t log_id) {
  if (loop_first_input_id_ > 0) return;
  store_.appendEvent({0, name_, kLoopInputEvent, nowNs(), nlohmann::json{{"message_id", log_id}}.dump()});
  loop_first_input_id_ = log_id;
}

void MapWorker::publishPose(const RobotPose& pose) {
  last_poses_[pose.robot_id] = pose;
  if (pose_sink_) pose_sink_(pose);
}

bool MapWorker::newPlace(FrameKind kind, const LoopPlace& place) {
  const auto key = std::pair{kind, place.robot_id};
  const auto last = last_frames_.find(key);
  if (last != last_frames_.end()) {
    const LoopPlace& before = last->second;
    if (place.pose && before.pose) {
      const Eigen::Isometry3d step = before.pose->inverse() * *place.pose;
      if (step.translation().norm() < kFrameSpacing_m && Eigen::AngleAxisd(step.linear()).angle() < kFrameSpacing_rad) {
        return false;
      }
    } else if (place.stamp_ns - before.stamp_ns < kFrameSpacing_ns) {
      return false;
    }
  }
  last_frames_[key] = place;
  return true;
}

void MapWorker::feedImage(int64_t log_id, const v1::RobotMessage& message, const std::string& robot_id, bool live) {
  if (!loop_feed_->accepts(FrameKind::kCamera)) return;
  const v1::CameraImage& image = message.image();
  // The camera's pose when the image carries one, else the robot's latest.
  LoopPlace place{robot_id, image.stamp_ns(), std::nullopt};
  if (image.has_camera_pose()) {
    place.pose = toIsometry(image.camera_pose());
  } else if (const auto it = last_poses_.find(robot_id); it != last_poses_.end()) {
    place.pose = it->second.pose;
  }
  if (!newPlace(FrameKind::kCamera, place)) return;
  noteLoopInput(log_id);
  // Decoded on the feed's thread, from a copy: the message goes once it is applied.
  auto copy = std::make_shared<const v1::CameraImage>(image);
  loop_feed_->push({FrameKind::kCamera, std::move(place), [copy] { return cameraGray(*copy); }}, !live);
}

void MapWorker::feedCloud(int64_t log_id, const v1::RobotMessage& message, const std::string& robot_id, bool live) {
  const v1::PointCloud& cloud = message.cloud();
  if (cloud.intensities().empty() || !loop_feed_->accepts(FrameKind::kIntensityPanorama)) return;
  const Eigen::Isometry3d sensor_pose = toIsometry(cloud.sensor_pose());
  if (!newPlace(FrameKind::kIntensityPanorama, {robot_id, cloud.stamp_ns(), sensor_pose})) return;
  noteLoopInput(log_id);
  // Projected on the feed's thread, from a copy: the message goes once it is applied.
  auto copy = std::make_shared<const v1::PointCloud>(cloud);
  loop_feed_->push({FrameKind::kIntensityPanorama, {robot_id, cloud.stamp_ns(), sensor_pose}, [copy, sensor_pose] {
                      // The panorama is taken around the sensor: points in its frame.
                      const Eigen::Isometry3f to_sensor = copy->frame() == v1::PointCloud::MAP
                                                              ? sensor_pose.inverse().cast<float>()
                                                              : Eigen::Isometry3f::Identity();
                      const int n = copy->xyz_m_size() / 3;
                      std::vector<Eigen::Vector3f> points(static_cast<size_t>(n));
                      for (int i = 0; i < n; ++i) {
                        points[i] = to_sensor * Eigen::Vector3f(copy->xyz_m(3 * i), copy->xyz_m(3 * i + 1),
                                                                copy->xyz_m(3 * i + 2));
                      }
                      cv::Mat point_index;
                      cv::Mat gray = loop::projectPanorama(
                          points, std::span<const float>(copy->intensities().data(), copy->intensities().size()),
                          loop::PanoramaOptions{}, point_index);
                      return PlaceImage(std::move(gray), loop::panoramaPoints(point_index, points));
                    }},
                   !live);
}

void MapWorker::feedPatch(int64_t log_id, const std::string& robot_id, int64_t stamp_ns,
                          const slam2d::Pose2& base_pose, bool live) {
  if (!loop_feed_->accepts(FrameKind::kReflectivityPatch)) return;
  LoopPlace place{robot_id, stamp_ns, slam2d::planarIsometry(base_pose)};
  if (!newPlace(FrameKind::kReflectivityPatch, place)) return;
  noteLoopInput(log_id);
  // Rendered now: the 2D map changes with the next scans.
  cv::Mat patch = slam2d_.reflectivityPatch(base_pose, loop::PatchOptions{});
  loop_feed_->push({FrameKind::kReflectivityPatch, std::move(place), [patch = std::move(patch)] { return patch; }},
                   !live);
}

void MapWorker::postClosures(const std::vector<slam2d::LoopClosure2d>& accepted,
                             const std::vector<slam2d::LoopClosure2d>& withdrawn) {
  // Stored by the feed's thread: a durable write per closure would hold this worker's acks back.
  const auto post = [&](const slam2d::LoopClosure2d& c, bool is_withdrawn) {
    std::optional<Eigen::Vector3d> ambiguous_direction;
    if (c.ambiguous_direction) ambiguous_direction = Eigen::Vector3d(c.ambiguous_direction->x(), c.ambiguous_direction->y(), 0.0);
    loop_feed_->post({name_, LoopSource::kGeometry, {c.query_trajectory, c.query_stamp_ns, slam2d::planarIsometry(c.query_pose)},
                      {c.match_trajectory, c.match_stamp_ns, slam2d::planarIsometry(c.match_pose)}, c.score,
                      slam2d::planarIsometry(c.relative), is_withdrawn, ambiguous_direction});
  };
  for (const slam2d::LoopClosure2d& c : accepted) post(c, false);
  for (const slam2d::LoopClosure2d& c : withdrawn) post(c, true);
}

void MapWorker::applyScan(int64_t log_id, const v1::RobotMessage& message, const std::string& robot_id,
                          bool in_map3d, bool live) {
  const v1::LaserScan2D& scan = message.scan();
  const std::optional<Laser2dSetup> laser = sensors_.laser(robot_id, message.seq(), scan.sensor());
  const std::optional<Slam2dResult> result = slam2d_.addScan(robot_id, scan, laser);
  if (!result) return;
  feedPatch(log_id, robot_id, scan.stamp_ns(), result->base_pose, live);
  // The scan in the 3D map: a planar cloud at the laser's mounting height above the map's z = 0.
  PlanarScan planar{scan.stamp_ns(), message.seq(), result->base_pose, result->scan.sensor_mount,
                    laser ? laser->z_m : 0.0, 0.0f, false};
  const slam2d::Pose2& sensor = result->sensor_pose;
  std::vector<Eigen::Vector3f> points;
  points.reserve(result->scan.ranges_m.size());
  const float range_min_m = std::max(result->scan.range_min_m, 0.0f);
  for (size_t i = 0; i < result->scan.ranges_m.size(); ++i) {
    const float r = result->scan.ranges_m[i];
    if (!std::isfinite(r) || r < range_min_m || r > result->scan.range_max_m) continue;
    const float a = result->scan.angles_rad[i];
    const Eigen::Vector2d p = sensor * Eigen::Vector2d(r * std::cos(a), r * std::sin(a));
    points.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(planar.height_m));
    planar.reach_m = std::max(planar.reach_m, r);
  }
  const Eigen::Vector3f origin(static_cast<float>(sensor.x_m), static_cast<float>(sensor.y_m),
                               static_cast<float>(planar.height_m));
  map3d::CellKey origin_cell;
  planar.in_map3d = !points.empty() && map_->grid().cellChecked(origin, origin_cell);
  planar_scans_[robot_id].push_back(planar);
  postClosures(result->closures, result->withdrawn_closures);
  if (!in_map3d) {
    if (planar.in_map3d) {
      map3d::InsertOptions options;
      options.threads = config_.maps.insert_threads;
      options.invalid_points = map3d::InvalidPoints::kSkip;
      const map3d::ScanStats stats = map_->insertScan(origin, points, options);
      metrics_.points_integrated.fetch_add(stats.points - stats.rejected_points, std::memory_order_relaxed);
    }
    const RobotPose pose{robot_id, name_, message.seq(), scan.stamp_ns(), slam2d::planarIsometry(result->base_pose)};
    pending_poses_.emplace_back(robot_id, toTrajectoryPose(pose));
    publishPose(pose);
    if (live && estimate_sink_) {
      v1::PoseEstimate estimate;
      estimate.set_seq(message.seq());
      estimate.set_stamp_ns(scan.stamp_ns());
      const Eigen::Quaterniond q(pose.pose.linear());
      estimate.mutable_pose()->mutable_position_m()->set_x(result->base_pose.x_m);
      estimate.mutable_pose()->mutable_position_m()->set_y(result->base_pose.y_m);
      estimate.mutable_pose()->mutable_orientation()->set_w(q.w());
      estimate.mutable_pose()->mutable_orientation()->set_z(q.z());
      estimate_sink_(robot_id, estimate);
    }
  }
  if (result->graph_changed) applyCorrection(in_map3d);
}

void MapWorker::applyCorrection(bool in_map3d) {
  const auto start = Clock::now();
  const double cell_m = map_->resolution();
  Eigen::AlignedBox2d region;  // where moved scans drew their planar clouds, before and after
  std::set<int32_t> rows;       // z cells of those clouds
  for (auto& [robot, scans] : planar_scans_) {
    const std::vector<slam2d::StampedPose2> corrected = slam2d_.trajectory(robot);
    if (corrected.size() != scans.size()) {
      spdlog::error("map {}: the SLAM corrected {} scans of {}, the map holds {}; not corrected", name_,
                    corrected.size(), robot, scans.size());
      continue;
    }
    for (size_t i = 0; i < scans.size(); ++i) {
      PlanarScan& s = scans[i];
      const slam2d::Pose2& p = corrected[i].pose;
      // Moved when some beam end may land in another 3D cell.
      const double shift_m = Eigen::Vector2d(p.x_m - s.base_pose.x_m, p.y_m - s.base_pose.y_m).norm() +
                             std::abs(slam2d::normalizeAngle(p.theta_rad - s.base_pose.theta_rad)) * s.reach_m;
      if (shift_m < cell_m / 2) continue;
      if (s.in_map3d) {
        for (const slam2d::Pose2& base : {s.base_pose, p}) {
          const slam2d::Pose2 laser = base * s.mount;
          const Eigen::Vector2d reach = Eigen::Vector2d::Constant(s.reach_m);
          region.extend(Eigen::Vector2d(laser.x_m, laser.y_m) - reach);
          region.extend(Eigen::Vector2d(laser.x_m, laser.y_m) + reach);
        }
        rows.insert(map_->grid().index(s.height_m));
      }
      s.base_pose = p;
      if (!in_map3d) {
        pending_poses_.emplace_back(robot, toTrajectoryPose({robot, name_, s.seq, s.stamp_ns, slam2d::planarIsometry(p)}));
      }
    }
    if (!in_map3d && !scans.empty()) {
      const PlanarScan& last = scans.back();
      publishPose({robot, name_, last.seq, last.stamp_ns, slam2d::planarIsometry(last.base_pose)});
    }
  }
  // Below the 3D snapshot the snapshot holds the planar rows as later scans left them.
  if (!in_map3d && !region.isEmpty()) rewritePlanarRows(region, rows);
  metrics_.trajectory_corrections.fetch_add(1, std::memory_order_relaxed);
  metrics_.correction_latency.observe(std::chrono::duration<double>(Clock::now() - start).count());
}

void MapWorker::rewritePlanarRows(const Eigen::AlignedBox2d& region_m, const std::set<int32_t>& rows) {
  const map3d::Grid& grid = map_->grid();
  const auto clampCell = [](int32_t c) { return std::clamp(c, -map3d::kCellLimit, map3d::kCellLimit - 1); };
  const int32_t x0 = clampCell(grid.index(region_m.min().x())), x1 = clampCell(grid.index(region_m.max().x()));
  const int32_t y0 = clampCell(grid.index(region_m.min().y())), y1 = clampCell(grid.index(region_m.max().y()));
  slam2d_.read([&](const Grid2dSource& grid2d) {
    const double r3 = grid.resolution(), r2 = grid2d.resolutionM();
    // A 3D cell takes the highest occupancy of the 2D cells under it (occupied if any is, like the
    // 3D map's own coarse levels), unknown when none of them is known.
    const auto value = [&](const map3d::CellKey& c) -> std::optional<float> {
      const int i0 = static_cast<int>(std::floor(c.x * r3 / r2 + 1e-9));
      const int i1 = static_cast<int>(std::floor((c.x + 1) * r3 / r2 - 1e-9));
      const int j0 = static_cast<int>(std::floor(c.y * r3 / r2 + 1e-9));
      const int j1 = static_cast<int>(std::floor((c.y + 1) * r3 / r2 - 1e-9));
      float best = -1.0f;
      for (int j = j0; j <= j1; ++j) {
        for (int i = i0; i <= i1; ++i) {
          const float p = grid2d.probability({i, j});
          if (std::isfinite(p)) best = std::max(best, p);
        }
      }
      if (best < 0.0f) return std::nullopt;
      const float p = std::clamp(best, 1e-4f, 1.0f - 1e-4f);
      return std::log(p / (1.0f - p));
    };
    for (const int32_t z : rows) map_->rewriteCells({x0, y0, z}, {x1, y1, z}, value);
    return 0;
  });
}

void MapWorker::flushTrajectories() {
  if (pending_poses_.empty()) return;
  std::map<std::string, std::vector<store::TrajectoryPose>> by_robot;
  for (auto& [robot, pose] : pending_poses_) by_robot[robot].push_back(pose);
  last_pose_flush_ = Clock::now();
  for (const auto& [robot, poses] : by_robot) store_.appendTrajectory(robot, poses);
  // Only once stored (writing a pose again replaces it): dropped on a failed write, say on a
  // full disk, they would be missing for good once a later snapshot covers their messages.
  pending_poses_.clear();
}

bool MapWorker::importBlocks(const map3d::MapBlocks& blocks, bool replace) {
  std::promise<bool> done;
  std::future<bool> result = done.get_future();
  {
    std::lock_guard lock(mutex_);
    if (stopping_) throw std::runtime_error("map " + name_ + " is stopping");
    queue_.push_back({0, nullptr, {}, [&] {
                        try {
                          done.set_value(replaceContent(blocks, replace));
                        } catch (...) {
                          done.set_exception(std::current_exception());
                        }
                      }});
  }
  wake_.notify_one();
  return result.get();
}

bool MapWorker::replaceContent(const map3d::MapBlocks& blocks, bool replace) {
  if (!replace && map_->stats().known_cells > 0) return false;
  // Durable first, from a copy of the new content: if the store fails, the live map is untouched.
  map3d::CuboidMap staged(map_->resolution(), map_->occupancyParams(), map_->fusionParams());
  replaceBlocksInSlices(staged, blocks);
  flushTrajectories();  // poses of messages inside the snapshot must not depend on the replay
  const int64_t applied = applied_id_.load();
  store_.putSnapshot({name_, applied, map3d::encodeMap(staged)});
  snapshot_id_ = applied;
  last_snapshot_ = Clock::now();
  metrics_.snapshots_written.fetch_add(1, std::memory_order_relaxed);
  // Blocks the import leaves out are emptied, not dropped: their new version tells the tile index.
  map3d::MapBlocks live = blocks;
  std::unordered_set<map3d::BlockKey, map3d::BlockKeyHash> filled;
  for (const auto& [key, cuboids] : blocks) filled.insert(key);
  map_->forEachBlockVersion([&](const map3d::BlockKey& key, uint64_t) {
    if (!filled.contains(key)) live.emplace_back(key, std::vector<map3d::PackedCuboid>{});
  });
  replaceBlocksInSlices(*map_, live);
  spdlog::info("map {}: 3D content replaced by an import of {} blocks", name_, blocks.size());
  return true;
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
