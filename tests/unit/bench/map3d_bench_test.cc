#include "map3d/map3d_bench.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

namespace rmap::bench {
namespace {

nlohmann::json runSmallBench(const std::string& extra_name, float tolerance) {
  Map3dBenchOptions o;
  o.source = "sim:building";
  o.resolution_m = 0.2;
  o.sensor_models = "both";
  o.fusion_tolerance = tolerance;
  o.sim.poses = 6;
  o.sim.rings = 16;
  o.sim.columns = 256;
  o.json_out = (std::filesystem::temp_directory_path() / ("rmap_bench_" + extra_name + ".json")).string();
  EXPECT_EQ(runMap3dBench(o), 0);
  std::ifstream in(o.json_out);
  return nlohmann::json::parse(in);
}

// The benchmark's own figures must hold together: the fields the issue lists,
// exactness with fusion off, ratios consistent with the absolute numbers.
TEST(Map3dBench, SimulatedRunReportsConsistentFigures) {
  const nlohmann::json r = runSmallBench("default", -1.0f);
  for (const char* key : {"dataset", "resolution_m", "points", "speedup", "memory_ratio", "agreement"}) {
    EXPECT_TRUE(r.contains(key)) << key;
  }
  EXPECT_EQ(r["points"].get<uint64_t>() > 0, true);
  EXPECT_EQ(r["fusion_off"]["agreement"].get<double>(), 1.0);
  EXPECT_GE(r["agreement"].get<double>(), 0.99);
  EXPECT_NEAR(r["speedup"].get<double>(),
              r["octomap"]["insert_s"].get<double>() / r["rmap"]["insert_s"].get<double>(), 1e-9);
  EXPECT_GT(r["rmap"]["insert_cpu_s"].get<double>(), 0.0);
  EXPECT_NEAR(r["speedup_cpu"].get<double>(),
              r["octomap"]["insert_cpu_s"].get<double>() / r["rmap"]["insert_cpu_s"].get<double>(), 1e-9);
  EXPECT_NEAR(r["memory_ratio"].get<double>(),
              r["rmap"]["memory_bytes"].get<double>() / r["octomap"]["memory_bytes"].get<double>(), 1e-9);
  EXPECT_LT(r["rmap"]["cuboids"].get<double>(), r["octomap"]["leaves"].get<double>());
  for (const char* map : {"rmap", "octomap"}) {
    EXPECT_GT(r["cv_accuracy"][map].get<double>(), 0.5);
    EXPECT_LE(r["cv_accuracy"][map].get<double>(), 1.0);
    EXPECT_GT(r["truth_accuracy"][map].get<double>(), 0.5);
  }
  EXPECT_EQ(r["cv_protocol"], "every 5th scan held out");
  // the endpoint model knows no free space: every known cell is occupied
  const nlohmann::json& e = r["endpoint_model"];
  EXPECT_EQ(e["rmap"]["known_cells"], e["octomap"]["known_cells"]);
  EXPECT_EQ(e["agreement"].get<double>(), 1.0);
}

TEST(Map3dBench, ZeroToleranceMeansOctomapExactly) {
  const nlohmann::json r = runSmallBench("exact", 0.0f);
  EXPECT_EQ(r["free_space"], "exact");
  EXPECT_EQ(r["agreement"].get<double>(), 1.0);
  EXPECT_EQ(r["cv_accuracy"]["rmap"], r["cv_accuracy"]["octomap"]);
  EXPECT_EQ(r["truth_accuracy"]["rmap"], r["truth_accuracy"]["octomap"]);
}

TEST(Map3dBench, UnknownSourceIsAClearError) {
  Map3dBenchOptions o;
  o.source = "sim:nowhere";
  EXPECT_THROW(runMap3dBench(o), std::runtime_error);
}

}  // namespace
}  // namespace rmap::bench
