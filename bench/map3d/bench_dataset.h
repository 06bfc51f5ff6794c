#pragma once
/// @file bench_dataset.h
/// Scan sources of `rmap-bench map3d`: real files and simulated runs.

#include <memory>
#include <string>
#include <vector>

#include "datasets/point_scan.h"
#include "sim/voxel_world.h"

namespace rmap::bench {

struct SimOptions {
  int poses = 100;      ///< trajectory length
  int rings = 64;       ///< lidar rings
  int columns = 1024;   ///< lidar columns
  double max_range_m = 30.0;
  double sensor_height_m = 1.3;  ///< lidar above the floor (a mast); lower ones squeeze through fewer gaps of geb079
  uint64_t seed = 1;
};

struct BenchDataset {
  std::string name;
  std::vector<datasets::PointScan> scans;
  std::shared_ptr<const sim::VoxelWorld> truth;  ///< simulated world, null for real data
};

/// Loads SOURCE: a `scan.dat`-style text cloud (optionally .bz2/.gz), a 3DTK
/// uos folder, `sim:geb079` (lidar driven through OctoMap's geb079.bt, read
/// from `shared_data_dir`), or `sim:building` (procedural building).
/// @throws std::runtime_error naming the source when it cannot be read
BenchDataset loadBenchDataset(const std::string& source, const SimOptions& sim, const std::string& shared_data_dir);

}  // namespace rmap::bench
