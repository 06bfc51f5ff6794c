// SimFeed: simulated lidar and 2D-laser robots streaming through RobotClient.

#include "client/sim_feed.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <condition_variable>
#include <mutex>
#include <numbers>
#include <optional>
#include <random>
#include <stdexcept>
#include <thread>
#include <unordered_map>

#include "client/laser2d_robot.h"
#include "client/robot_client.h"
#include "sim/trajectory.h"

namespace rmap::client {
namespace {

using Clock = std::chrono::steady_clock;

constexpr double kSensorHeight_m = 1.3;  ///< a lidar on a ground robot
constexpr double kLidarMaxRange_m = 20.0;
constexpr double kLidarFov_deg = 15.0;   ///< ± elevation, as a 16-ring spinning lidar
constexpr const char* kLidarName = "lidar";
constexpr const char* kLidarModel = "sim-lidar-16";
/// A wheeled robot's laser: it stays on its storey, a scan every 0.25 m.
constexpr double kLaser2dStep_m = 0.25;

sim::LidarModel lidarModel(const SimFeedOptions& o) {
  sim::LidarModel model;
  model.rings = o.lidar_rings;
  model.columns = o.lidar_columns;
  model.fov_up_deg = kLidarFov_deg;
  model.fov_down_deg = -kLidarFov_deg;
  model.max_range_m = kLidarMaxRange_m;
  return model;
}

sim::TrajectoryOptions trajectoryOptions(const SimFeedOptions& o) {
  sim::TrajectoryOptions t;
  t.sensor_height_m = kSensorHeight_m;
  t.num_poses = o.poses;
  return t;
}

Laser2dRobotOptions laser2dOptions(const SimFeedOptions& o) {
  Laser2dRobotOptions l;
  l.laser = o.laser2d_model;
  return l;
}

sim::TrajectoryOptions laser2dTourOptions(const SimFeedOptions& o) {
  sim::TrajectoryOptions t;
  t.sensor_height_m = laser2dOptions(o).mount_height_m;
  t.max_step_m = 0.0;  // no stairs: a 2D laser maps one storey
  t.step_m = kLaser2dStep_m;
  t.num_poses = o.poses;
  return t;
}

/// Hello of robot `index` with its sensor.
rmap::v1::Hello makeHello(const SimFeedOptions& o, int index, const rmap::v1::SensorDescription& sensor) {
  rmap::v1::Hello hello;
  hello.set_robot_id(o.robot_prefix + "-" + std::to_string(index));
  hello.set_map(o.shared_map ? o.map_prefix : o.map_prefix + "-" + std::to_string(index));
  hello.set_resolution_m(o.resolution_m);
  *hello.add_sensors() = sensor;
  return hello;
}

rmap::v1::SensorDescription lidarSensor() {
  rmap::v1::SensorDescription lidar;
  lidar.set_name(kLidarName);
  lidar.set_kind(rmap::v1::SensorDescription::LIDAR_3D);
  lidar.set_model(kLidarModel);
  lidar.mutable_mount()->mutable_orientation()->set_w(1.0);  // the clouds are in the map frame anyway
  return lidar;
}

/// One scan at `pose` as a map-frame cloud (stamp left for send time).
rmap::v1::RobotMessage makeCloud(const sim::VoxelWorld& world, const Eigen::Isometry3d& pose,
                                 const sim::LidarModel& model, std::mt19937_64& rng) {
  const sim::LidarScan scan = sim::simulateLidar(world, pose, model, rng);
  rmap::v1::RobotMessage message;
  rmap::v1::PointCloud& cloud = *message.mutable_cloud();
  cloud.set_sensor(kLidarName);
  cloud.set_frame(rmap::v1::PointCloud::MAP);
  rmap::v1::Pose3& sensor_pose = *cloud.mutable_sensor_pose();
  const Eigen::Vector3d p = pose.translation();
  sensor_pose.mutable_position_m()->set_x(p.x());
  sensor_pose.mutable_position_m()->set_y(p.y());
  sensor_pose.mutable_position_m()->set_z(p.z());
  const Eigen::Quaterniond q(pose.rotation());
  sensor_pose.mutable_orientation()->set_w(q.w());
  sensor_pose.mutable_orientation()->set_x(q.x());
  sensor_pose.mutable_orientation()->set_y(q.y());
  sensor_pose.mutable_orientation()->set_z(q.z());
  auto& xyz = *cloud.mutable_xyz_m();
  xyz.Reserve(static_cast<int>(3 * scan.points_m.size()));
  for (const Eigen::Vector3f& point : scan.points_m) {
    xyz.Add(point.x());
    xyz.Add(point.y());
    xyz.Add(point.z());
  }
  cloud.mutable_intensities()->Add(scan.intensities.begin(), scan.intensities.end());
  return message;
}

int64_t wallClockNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// What the robot threads share.
struct Totals {
  std::atomic<uint64_t> clouds_sent{0};
  std::atomic<uint64_t> clouds_acked{0};
  std::atomic<uint64_t> points_sent{0};
  std::atomic<uint64_t> points_acked{0};
  std::atomic<uint64_t> scans_sent{0};
  std::atomic<uint64_t> scans_acked{0};
  std::mutex mutex;  ///< guards the rest
  std::vector<double> ack_latencies_ms;
  std::vector<std::string> errors;
  uint64_t pose_estimates = 0;
  double pose_error_sum_m = 0.0;
  double pose_error_max_m = 0.0;
  double heading_error_max_rad = 0.0;

  void addPoseError(double error_m, double heading_error_rad) {
    std::lock_guard lock(mutex);
    ++pose_estimates;
    pose_error_sum_m += error_m;
    pose_error_max_m = std::max(pose_error_max_m, error_m);
    heading_error_max_rad = std::max(heading_error_max_rad, heading_error_rad);
  }

  void addError(std::string error) {
    std::lock_guard lock(mutex);
    errors.push_back(std::move(error));
  }
};

/// What one robot drives: a lidar robot's poses and, in benchmark mode, the
/// clouds it cycles over; or a 2D-laser robot.
struct RobotPlan {
  std::vector<Eigen::Isometry3d> poses;
  std::mt19937_64 rng;
  std::vector<rmap::v1::RobotMessage> cache;
  std::optional<Laser2dRobot> laser2d;
};

/// Plans the trajectory and simulates the cached clouds up front, so the
/// timed part of a benchmark feed measures the server, not the simulator.
RobotPlan planRobot(const SimScene& scene, const SimFeedOptions& o, int index) {
  std::seed_seq seeds{o.seed, static_cast<uint64_t>(index)};
  const uint64_t tour_seed = o.seed + static_cast<uint64_t>(index);
  if (index >= o.robots) {
    RobotPlan plan;
    plan.laser2d.emplace(scene.world, sim::planTrajectory(scene.world, laser2dTourOptions(o), tour_seed),
                         laser2dOptions(o), std::mt19937_64(seeds)());
    return plan;
  }
  RobotPlan plan{sim::planTrajectory(scene.world, trajectoryOptions(o), tour_seed), std::mt19937_64(seeds), {}, {}};
  const size_t cached = o.max_clouds == 0 ? o.precompute_clouds
                                          : std::min<size_t>(o.precompute_clouds, static_cast<size_t>(o.max_clouds));
  const sim::LidarModel model = lidarModel(o);
  for (size_t k = 0; k < cached; ++k) {
    plan.cache.push_back(makeCloud(scene.world, plan.poses[k % plan.poses.size()], model, plan.rng));
  }
  return plan;
}

/// One robot from Hello to its last ack; never throws (failures go to totals.errors).
void runRobot(const SimScene& scene, const SimFeedOptions& o, int index, RobotPlan& plan, Clock::time_point end,
              Totals& totals) {
  RobotClientOptions client_options;
  client_options.server_url = o.server_url;
  client_options.token = o.token;
  client_options.hello = makeHello(o, index, plan.laser2d ? plan.laser2d->sensor() : lidarSensor());
  client_options.max_in_flight = o.max_in_flight;
  client_options.timeout = o.timeout;
  const std::string robot_id = client_options.hello.robot_id();

  /// A message in flight: a cloud's point count, or a scan's true base pose.
  struct InFlight {
    uint64_t points = 0;
    std::optional<Eigen::Vector3d> base_truth;
  };
  std::vector<double> latencies_ms;
  std::mutex points_mutex;
  std::unordered_map<uint64_t, InFlight> in_flight;
  try {
    RobotClient client(client_options);
    // Callbacks run on the client's I/O thread.
    client.onAck([&](const rmap::v1::Ack& ack, std::chrono::nanoseconds latency) {
      InFlight acked;
      {
        std::lock_guard lock(points_mutex);
        if (const auto it = in_flight.find(ack.seq()); it != in_flight.end()) {
          acked = it->second;
          in_flight.erase(it);
        }
        latencies_ms.push_back(std::chrono::duration<double, std::milli>(latency).count());
      }
      (acked.base_truth ? totals.scans_acked : totals.clouds_acked).fetch_add(1, std::memory_order_relaxed);
      totals.points_acked.fetch_add(acked.points, std::memory_order_relaxed);
    });
    // The server's 2D SLAM answers each scan with a PoseEstimate before its ack.
    client.onPose([&](const rmap::v1::PoseEstimate& estimate) {
      std::optional<Eigen::Vector3d> truth;
      {
        std::lock_guard lock(points_mutex);
        if (const auto it = in_flight.find(estimate.seq()); it != in_flight.end()) truth = it->second.base_truth;
      }
      if (!truth) return;
      const rmap::v1::Pose3& pose = estimate.pose();
      const Eigen::Vector2d position(pose.position_m().x(), pose.position_m().y());
      const Eigen::Quaterniond q(pose.orientation().w(), pose.orientation().x(), pose.orientation().y(),
                                 pose.orientation().z());
      const Eigen::Vector3d x_axis = q.normalized() * Eigen::Vector3d::UnitX();
      const double yaw = std::atan2(x_axis.y(), x_axis.x());
      totals.addPoseError((position - truth->head<2>()).norm(), std::abs(std::remainder(yaw - truth->z(), 2 * std::numbers::pi)));
    });
    client.onError([&](const rmap::v1::Error& error) {
      {
        std::lock_guard lock(points_mutex);
        in_flight.erase(error.seq());  // answered, though refused
      }
      totals.addError(robot_id + ": seq " + std::to_string(error.seq()) + ": " + error.code() + ": " +
                      error.message() + (error.fatal() ? " (fatal)" : ""));
    });

    const sim::LidarModel model = lidarModel(o);

    // A single sender: sequence numbers follow Welcome::last_durable_seq one by one,
    // so each message's record is filed before its estimate or ack can arrive.
    const uint64_t durable = client.connect().last_durable_seq();
    uint64_t next_seq = durable + 1;
    // A 2D-laser robot sends one scan per step, numbered from 1: one the
    // server already holds steps resumes its tour (and odometry) after them.
    if (plan.laser2d) plan.laser2d->skip(durable);
    const auto period = o.rate_hz > 0 ? std::chrono::duration_cast<Clock::duration>(
                                            std::chrono::duration<double>(1.0 / o.rate_hz))
                                      : Clock::duration::zero();
    // Robots are not synchronised: each starts at its own offset into the period.
    Clock::time_point due = Clock::now() + period * index / (o.robots + o.laser2d_robots);
    for (uint64_t k = 0; o.max_clouds == 0 || k < o.max_clouds; ++k) {
      if (due >= end || Clock::now() >= end) break;
      std::this_thread::sleep_until(due);
      rmap::v1::RobotMessage message;
      InFlight record;
      if (plan.laser2d) {
        Laser2dStep step = plan.laser2d->next();
        *message.mutable_scan() = std::move(step.scan);
        message.mutable_scan()->set_stamp_ns(wallClockNs());
        record.base_truth = step.base_truth;
      } else {
        message = plan.cache.empty() ? makeCloud(scene.world, plan.poses[k % plan.poses.size()], model, plan.rng)
                                     : plan.cache[k % plan.cache.size()];
        message.mutable_cloud()->set_stamp_ns(wallClockNs());
        record.points = static_cast<uint64_t>(message.cloud().xyz_m_size() / 3);
      }
      {
        std::lock_guard lock(points_mutex);
        in_flight[next_seq] = record;
      }
      const uint64_t seq = client.send(std::move(message));
      if (seq != next_seq) throw std::logic_error("sequence numbers skipped: sent " + std::to_string(seq));
      ++next_seq;
      (record.base_truth ? totals.scans_sent : totals.clouds_sent).fetch_add(1, std::memory_order_relaxed);
      totals.points_sent.fetch_add(record.points, std::memory_order_relaxed);
      // No catch-up bursts after a slow spell: the schedule restarts from now.
      due = std::max(due + period, Clock::now());
    }
    if (!client.waitAllAcked(o.timeout)) {
      size_t unanswered = 0;
      {
        std::lock_guard lock(points_mutex);
        unanswered = in_flight.size();
      }
      totals.addError(robot_id + ": " + std::to_string(unanswered) + " messages unacknowledged at the end (" +
                      (client.connected() ? "timed out after " + std::to_string(o.timeout.count()) + " ms"
                                          : std::string("connection closed")) + ")");
    }
    client.close();
  } catch (const std::exception& e) {
    totals.addError(robot_id + ": " + e.what());
  }
  // The client and its I/O thread are gone: no callback touches latencies_ms any more.
  std::lock_guard lock(totals.mutex);
  totals.ack_latencies_ms.insert(totals.ack_latencies_ms.end(), latencies_ms.begin(), latencies_ms.end());
}

}  // namespace

SimScene makeSimScene(uint64_t seed, double voxel_m) {
  sim::BuildingOptions options;
  options.voxel_m = voxel_m;
  options.floors = 2;  // stairs give the robots a second level to map
  sim::BuildingLayout layout;
  sim::VoxelWorld world = sim::makeBuilding(options, seed, &layout);
  extendMarkersToLaserPlane(world, layout, options.floor_height_m, Laser2dRobotOptions{}.mount_height_m);
  return SimScene{std::move(world), std::move(layout)};
}

SimFeedResult runSimFeed(const SimScene& scene, const SimFeedOptions& options) {
  if (options.robots < 0) throw std::invalid_argument("robots must be >= 0");
  if (options.laser2d_robots < 0) throw std::invalid_argument("laser2d_robots must be >= 0");
  if (options.robots + options.laser2d_robots < 1) {
    throw std::invalid_argument("robots + laser2d_robots must be at least 1");
  }
  if (!(options.rate_hz >= 0.0) || !std::isfinite(options.rate_hz)) {
    throw std::invalid_argument("rate_hz must be finite and >= 0");
  }
  lidarModel(options).validate();
  trajectoryOptions(options).validate();
  laser2dOptions(options).validate();
  laser2dTourOptions(options).validate();

  const int robots = options.robots + options.laser2d_robots;
  std::vector<RobotPlan> plans(static_cast<size_t>(robots));
  {
    std::vector<std::exception_ptr> failures(plans.size());
    std::vector<std::thread> planners;
    for (size_t i = 0; i < plans.size(); ++i) {
      planners.emplace_back([&, i] {
        try {
          plans[i] = planRobot(scene, options, static_cast<int>(i));
        } catch (...) {
          failures[i] = std::current_exception();
        }
      });
    }
    for (std::thread& planner : planners) planner.join();
    for (const std::exception_ptr& failure : failures) {
      if (failure) std::rethrow_exception(failure);
    }
  }

  Totals totals;
  const Clock::time_point start = Clock::now();
  const Clock::time_point end = start + options.duration;
  std::mutex mutex;
  std::condition_variable cv;
  int running = robots;
  std::vector<std::thread> threads;
  threads.reserve(static_cast<size_t>(robots));
  for (int i = 0; i < robots; ++i) {
    threads.emplace_back([&, i] {
      runRobot(scene, options, i, plans[static_cast<size_t>(i)], end, totals);
      std::lock_guard lock(mutex);
      --running;
      cv.notify_all();
    });
  }
  const auto elapsed_s = [&start] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  {
    std::unique_lock lock(mutex);
    while (!cv.wait_for(lock, std::chrono::seconds(1), [&running] { return running == 0; })) {
      if (!options.on_progress) continue;
      lock.unlock();
      SimFeedProgress progress{elapsed_s(), totals.clouds_sent.load(), totals.clouds_acked.load(),
                               totals.points_acked.load(), totals.scans_sent.load()};
      {
        std::lock_guard totals_lock(totals.mutex);
        progress.pose_estimates = totals.pose_estimates;
        if (totals.pose_estimates > 0) progress.pose_error_mean_m = totals.pose_error_sum_m / totals.pose_estimates;
      }
      options.on_progress(progress);
      lock.lock();
    }
  }
  for (std::thread& thread : threads) thread.join();

  SimFeedResult result;
  result.wall_s = elapsed_s();
  result.clouds_sent = totals.clouds_sent.load();
  result.clouds_acked = totals.clouds_acked.load();
  result.points_sent = totals.points_sent.load();
  result.scans_sent = totals.scans_sent.load();
  result.scans_acked = totals.scans_acked.load();
  result.pose_estimates = totals.pose_estimates;
  if (totals.pose_estimates > 0) result.pose_error_mean_m = totals.pose_error_sum_m / totals.pose_estimates;
  result.pose_error_max_m = totals.pose_error_max_m;
  result.heading_error_max_rad = totals.heading_error_max_rad;
  result.ack_latencies_ms = std::move(totals.ack_latencies_ms);
  result.errors = std::move(totals.errors);
  return result;
}

}  // namespace rmap::client
