#pragma once
/// @file map3d_bench.h
/// `rmap-bench map3d`: rmap's cuboid map against OctoMap on the same scans.

#include <string>

#include "map3d/bench_dataset.h"

namespace rmap::bench {

struct Map3dBenchOptions {
  std::string source;               ///< see loadBenchDataset
  double resolution_m = 0.1;
  float fusion_tolerance = -1.0f;   ///< log-odds; < 0: the library default
  int fuse_after_scans = -1;        ///< < 0: the library default
  int threads = 1;                  ///< for both maps
  double max_range_m = -1.0;        ///< metres; < 0 unlimited
  std::string sensor_models = "both";  ///< beam | endpoint | both
  /// exact | stop-at-freed | auto (exact when the fusion tolerance is 0, so
  /// that "fusion off" means OctoMap's map cell for cell)
  std::string free_space = "auto";
  std::string json_out;             ///< empty: no file
  std::string shared_data_dir;
  SimOptions sim;
};

/// Runs the comparison, prints a table, writes JSON. @return process exit code
int runMap3dBench(const Map3dBenchOptions& options);

}  // namespace rmap::bench
