#include "map3d/bench_dataset.h"

#include <filesystem>
#include <iostream>
#include <random>
#include <stdexcept>

#include "datasets/compressed_file.h"
#include "datasets/uos_3dtk.h"
#include "datasets/xyz_text.h"
#include "map3d/octomap_bt.h"
#include "sim/bt_world.h"
#include "sim/building.h"
#include "sim/lidar.h"
#include "sim/trajectory.h"

namespace rmap::bench {
namespace {

BenchDataset simulate(const std::string& name, std::shared_ptr<const sim::VoxelWorld> world, const SimOptions& o) {
  BenchDataset data;
  data.name = name + " (" + std::to_string(o.rings) + "x" + std::to_string(o.columns) + " lidar, " +
              std::to_string(o.poses) + " poses)";
  sim::TrajectoryOptions traj;
  traj.num_poses = o.poses;
  traj.sensor_height_m = o.sensor_height_m;
  const std::vector<Eigen::Isometry3d> poses = sim::planTrajectory(*world, traj, o.seed);
  sim::LidarModel lidar;
  lidar.rings = o.rings;
  lidar.columns = o.columns;
  lidar.max_range_m = o.max_range_m;
  std::mt19937_64 rng(o.seed);
  for (const Eigen::Isometry3d& pose : poses) {
    sim::LidarScan scan = sim::simulateLidar(*world, pose, lidar, rng);
    data.scans.push_back({scan.sensor_origin_m, std::move(scan.points_m)});
  }
  data.truth = std::move(world);
  return data;
}

}  // namespace

BenchDataset loadBenchDataset(const std::string& source, const SimOptions& sim_options,
                              const std::string& shared_data_dir) {
  if (source == "sim:building") {
    auto world = std::make_shared<sim::VoxelWorld>(sim::makeBuilding(sim::BuildingOptions{}, sim_options.seed));
    return simulate("sim:building", std::move(world), sim_options);
  }
  if (source == "sim:geb079") {
    const std::string path = shared_data_dir + "/octomap/geb079.bt";
    if (!std::filesystem::exists(path)) throw std::runtime_error("sim:geb079 needs " + path + " (not found)");
    const map3d::BtTree tree = map3d::parseBt(datasets::readFileMaybeCompressed(path));
    auto world = std::make_shared<sim::VoxelWorld>(sim::worldFromBt(tree, 0.5f, sim_options.seed));
    return simulate("sim:geb079", std::move(world), sim_options);
  }
  if (source.rfind("sim:", 0) == 0) throw std::runtime_error("unknown simulated source " + source);
  if (std::filesystem::is_directory(source)) {
    BenchDataset data{"3dtk:" + std::filesystem::path(source).filename().string(), datasets::readUos3dtk(source), {}};
    return data;
  }
  return {std::filesystem::path(source).filename().string(), datasets::readXyzText(source), {}};
}

}  // namespace rmap::bench
