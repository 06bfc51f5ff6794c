#include "map3d/cuboid_map.h"

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <atomic>
#include <iostream>
#include <cmath>
#include <random>
#include <thread>

namespace rmap::map3d {
namespace {

struct Scan {
  Eigen::Vector3f origin;
  std::vector<Eigen::Vector3f> points;
};

/// Rays from a sensor inside a 6×5×3 m box room to its walls, with a pillar.
std::vector<Scan> roomScans(int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Scan> scans;
  for (int s = 0; s < count; ++s) {
    Scan scan{{1.0f + 4.0f * u(rng), 1.0f + 3.0f * u(rng), 1.0f + 0.5f * u(rng)}, {}};
    for (int i = 0; i < 3000; ++i) {
      const float az = 6.2831853f * u(rng), el = -0.9f + 1.6f * u(rng);
      const Eigen::Vector3f d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      float t = 1e9f;  // distance to the box walls [0,6]×[0,5]×[0,3]
      for (int a = 0; a < 3; ++a) {
        const float hi = a == 0 ? 6.0f : (a == 1 ? 5.0f : 3.0f);
        if (d[a] > 1e-6f) t = std::min(t, (hi - scan.origin[a]) / d[a]);
        if (d[a] < -1e-6f) t = std::min(t, (0.0f - scan.origin[a]) / d[a]);
      }
      scan.points.push_back(scan.origin + d * (t + 0.02f * (u(rng) - 0.5f)));
    }
    scans.push_back(std::move(scan));
  }
  return scans;
}

octomap::point3d op(const Eigen::Vector3f& p) { return {p.x(), p.y(), p.z()}; }

void insertAll(CuboidMap& map, const std::vector<Scan>& scans, int threads = 1) {
  for (const Scan& s : scans) map.insertScan(s.origin, s.points, {threads, InvalidPoints::kReject});
}

/// Every cell known to either map has the same state and, with tolerance 0,
/// bit-identical log-odds.
void expectSameAsOctomap(const CuboidMap& map, const octomap::OcTree& tree, bool exact_values) {
  uint64_t rmap_cells = 0;
  map.forEachKnownCell([&](const CellKey& c, float v) {
    ++rmap_cells;
    const octomap::OcTreeNode* n =
        tree.search(octomap::OcTreeKey(c.x + 32768, c.y + 32768, c.z + 32768));
    ASSERT_NE(n, nullptr) << "cell " << c.x << "," << c.y << "," << c.z << " unknown to OctoMap";
    ASSERT_EQ(tree.isNodeOccupied(n), v >= 0.0f);
    if (exact_values) {
      ASSERT_EQ(n->getLogOdds(), v);
    }
  });
  uint64_t octo_cells = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    const uint64_t s = uint64_t{1} << (16 - it.getDepth());
    octo_cells += s * s * s;
  }
  EXPECT_EQ(rmap_cells, octo_cells);
}

TEST(CuboidMap, ZeroToleranceEqualsOctomapCellForCell) {
  const auto scans = roomScans(6, 1);
  OccupancyParams exact;
  exact.free_space_tracing = FreeSpaceTracing::kOctomapExact;
  for (int fuse_after : {0, 2, 100}) {
    for (int threads : {1, 2}) {
      CuboidMap map(0.1, exact, {0.0f, fuse_after});
      insertAll(map, scans, threads);
      octomap::OcTree tree(0.1);
      for (const Scan& s : scans) {
        octomap::Pointcloud pc;
        for (const auto& p : s.points) pc.push_back(op(p));
        tree.insertPointCloud(pc, op(s.origin));
      }
      expectSameAsOctomap(map, tree, true);
      map.fuseAll(threads);
      expectSameAsOctomap(map, tree, true);
    }
  }
}

TEST(CuboidMap, OccupiedWinsAndEachCellChangesOncePerScan) {
  for (FreeSpaceTracing tracing : {FreeSpaceTracing::kOctomapExact, FreeSpaceTracing::kStopAtFreed}) {
  OccupancyParams params;
  params.free_space_tracing = tracing;
  CuboidMap map(1.0, params, {0.0f, 100});
  // the first ray ends in cell (2,0,0), which the second ray crosses; both cross (1,0,0)
  const std::vector<Eigen::Vector3f> points = {{2.5f, 0.5f, 0.5f}, {4.5f, 0.5f, 0.5f}};
  map.insertScan({0.5f, 0.5f, 0.5f}, points);
  const OccupancyParams p;
  EXPECT_EQ(map.queryCell({2, 0, 0}).log_odds, p.hit_log_odds);
  EXPECT_EQ(map.queryCell({2, 0, 0}).state, CellState::kOccupied);
  EXPECT_EQ(map.queryCell({1, 0, 0}).log_odds, p.miss_log_odds);
  EXPECT_EQ(map.queryCell({3, 0, 0}).state, CellState::kFree);
  EXPECT_EQ(map.queryCell({4, 0, 0}).state, CellState::kOccupied);
  EXPECT_EQ(map.queryCell({5, 0, 0}).state, CellState::kUnknown);
  EXPECT_EQ(map.queryCell({0, 0, 0}).log_odds, p.miss_log_odds);  // the sensor's cell, freed once
  }
}

// Early-stopping walks free almost exactly the cells OctoMap frees.
TEST(CuboidMap, StopAtFreedTracingStaysCloseToExact) {
  const auto scans = roomScans(6, 2);
  OccupancyParams exact_params;
  exact_params.free_space_tracing = FreeSpaceTracing::kOctomapExact;
  CuboidMap exact(0.05, exact_params, {0.0f, 100});
  CuboidMap fast(0.05, {}, {0.0f, 100});
  insertAll(exact, scans);
  insertAll(fast, scans);
  uint64_t cells = 0, same = 0;
  exact.forEachKnownCell([&](const CellKey& c, float v) {
    ++cells;
    same += fast.queryCell(c).state == (v >= 0.0f ? CellState::kOccupied : CellState::kFree);
  });
  const uint64_t union_cells = cells + fast.stats().known_cells - same;  // every shared known cell agrees here
  EXPECT_GE(static_cast<double>(same) / union_cells, 0.99);
  EXPECT_EQ(fast.stats().occupied_cells, exact.stats().occupied_cells);
}

TEST(CuboidMap, ClampsLogOdds) {
  CuboidMap map(1.0);
  const std::vector<Eigen::Vector3f> points = {{3.5f, 0.5f, 0.5f}};
  for (int i = 0; i < 20; ++i) map.insertScan({0.5f, 0.5f, 0.5f}, points);
  const OccupancyParams p;
  EXPECT_EQ(map.queryCell({3, 0, 0}).log_odds, p.clamp_max_log_odds);
  EXPECT_EQ(map.queryCell({1, 0, 0}).log_odds, p.clamp_min_log_odds);
}

TEST(CuboidMap, MaxRangeClearsWithoutEndpoint) {
  OccupancyParams p;
  p.max_range_m = 3.0;
  CuboidMap map(1.0, p);
  const std::vector<Eigen::Vector3f> points = {{10.5f, 0.5f, 0.5f}};
  const ScanStats stats = map.insertScan({0.5f, 0.5f, 0.5f}, points);
  EXPECT_EQ(stats.max_range_rays, 1u);
  EXPECT_EQ(stats.occupied_cells, 0u);
  EXPECT_EQ(map.queryCell({2, 0, 0}).state, CellState::kFree);
  EXPECT_EQ(map.queryCell({3, 0, 0}).state, CellState::kUnknown);  // the truncated end cell is not freed
  EXPECT_EQ(map.queryCell({10, 0, 0}).state, CellState::kUnknown);
}

TEST(CuboidMap, EndpointModelMarksNoFreeSpace) {
  OccupancyParams p;
  p.sensor_model = SensorModel::kEndpoint;
  CuboidMap map(0.1, p);
  insertAll(map, roomScans(2, 3));
  const MapStats s = map.stats();
  EXPECT_GT(s.known_cells, 0u);
  EXPECT_EQ(s.known_cells, s.occupied_cells);
}

TEST(CuboidMap, DefaultFusionStaysWithinToleranceAndShrinksTheMap) {
  const auto scans = roomScans(8, 5);
  CuboidMap exact(0.05, {}, {0.0f, 1000});
  CuboidMap fused(0.05);
  insertAll(exact, scans);
  insertAll(fused, scans);
  const uint64_t hot_bytes = exact.memoryBytes();
  exact.fuseAll();
  fused.fuseAll();
  std::cout << "hot " << hot_bytes << " B; exact " << exact.memoryBytes() << " B " << exact.stats().cuboids
            << " cuboids; fused " << fused.memoryBytes() << " B " << fused.stats().cuboids << " cuboids; "
            << exact.stats().known_cells << " cells" << std::endl;
  EXPECT_LT(exact.memoryBytes(), hot_bytes);
  EXPECT_LT(fused.memoryBytes(), exact.memoryBytes());
  EXPECT_LT(fused.stats().cuboids, exact.stats().cuboids);
  EXPECT_LT(exact.stats().cuboids, exact.stats().known_cells);
  uint64_t cells = 0, same_state = 0;
  const float half_tolerance = fused.fusionParams().tolerance_log_odds / 2;
  exact.forEachKnownCell([&](const CellKey& c, float v) {
    ++cells;
    const CellQuery q = fused.queryCell(c);
    same_state += q.state == (v >= 0.0f ? CellState::kOccupied : CellState::kFree);
    // fused values drift by at most half the tolerance per fusion; updates after a fusion may add more
    EXPECT_LE(std::abs(q.log_odds - v), 4 * half_tolerance + 1e-5f);
  });
  EXPECT_EQ(cells, fused.stats().known_cells);
  EXPECT_GE(static_cast<double>(same_state) / cells, 0.995);
}

TEST(CuboidMap, UpdatesSplitFusedCuboids) {
  CuboidMap map(1.0, {}, {0.0f, 0});
  std::vector<Eigen::Vector3f> wall;
  for (int y = 0; y < 8; ++y) wall.push_back({8.5f, y + 0.5f, 0.5f});
  map.insertScan({0.5f, 3.5f, 0.5f}, wall);
  const CellQuery before = map.queryCell({4, 3, 0});
  ASSERT_EQ(before.state, CellState::kFree);
  // a new obstacle in the middle of free space splits its cuboid
  const std::vector<Eigen::Vector3f> obstacle = {{4.5f, 3.5f, 0.5f}};
  for (int i = 0; i < 2; ++i) map.insertScan({0.5f, 3.5f, 0.5f}, obstacle);
  const CellQuery after = map.queryCell({4, 3, 0});
  EXPECT_EQ(after.state, CellState::kOccupied);
  EXPECT_EQ(after.cuboid.min, (CellKey{4, 3, 0}));
  EXPECT_EQ(after.cuboid.max, (CellKey{4, 3, 0}));
  EXPECT_EQ(map.queryCell({4, 2, 0}).state, CellState::kFree);
}

TEST(CuboidMap, PointBoxRayAndLevelOfDetailQueries) {
  CuboidMap map(0.1);
  insertAll(map, roomScans(6, 7));
  map.fuseAll();
  // point query: the wall at x = 6 m is occupied, the middle of the room is free
  const CellQuery wall = map.query({5.99, 2.5, 1.5});
  EXPECT_EQ(wall.state, CellState::kOccupied);
  EXPECT_GT(wall.probability, 0.5);
  const CellQuery inside = map.query({3.05, 2.55, 1.05});
  EXPECT_EQ(inside.state, CellState::kFree);
  for (int a = 0; a < 3; ++a) {
    EXPECT_LE(inside.cuboid.min[a], map.grid().index(std::array{3.05, 2.55, 1.05}[a]));
    EXPECT_GE(inside.cuboid.max[a], map.grid().index(std::array{3.05, 2.55, 1.05}[a]));
  }
  EXPECT_EQ(map.query({50.0, 0.0, 0.0}).state, CellState::kUnknown);
  EXPECT_EQ(map.query({NAN, 0.0, 0.0}).state, CellState::kUnknown);

  // box query: the cuboids of the whole map hold every known cell exactly once
  CellKey lo, hi;
  ASSERT_TRUE(map.bounds(lo, hi));
  uint64_t cells = 0;
  map.forEachCuboid(lo, hi, [&](const CuboidBox& c) {
    cells += uint64_t(c.max.x - c.min.x + 1) * (c.max.y - c.min.y + 1) * (c.max.z - c.min.z + 1);
    return true;
  });
  EXPECT_EQ(cells, map.stats().known_cells);
  const auto box = map.queryBox(Eigen::AlignedBox3d(Eigen::Vector3d(5.8, 2.0, 1.0), Eigen::Vector3d(6.2, 2.2, 1.2)));
  ASSERT_FALSE(box.empty());
  bool has_occupied = false;
  for (const CuboidBox& c : box) {
    has_occupied |= c.log_odds >= 0.0f;
    EXPECT_TRUE(c.max.x >= 58 && c.min.x <= 62 && c.max.y >= 20 && c.min.y <= 22);
  }
  EXPECT_TRUE(has_occupied);
  EXPECT_EQ(map.queryBox(Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(6, 5, 3)), 3).size(), 3u);

  // ray cast from the room centre along +x hits the wall at about 3 m
  const RayCastResult ray = map.castRay({3.05, 2.55, 1.55}, {1, 0, 0}, 20.0, false);
  ASSERT_EQ(ray.outcome, RayCastResult::Outcome::kHitOccupied);
  EXPECT_NEAR(ray.distance_m, 2.95, 0.15);
  EXPECT_NEAR(ray.cell.x, 59.5, 1.0);  // the wall at 6 m, scanned with ±1 cm noise
  const RayCastResult outward = map.castRay({3.05, 2.55, 1.55}, {0, 0, 1}, 1.0, false);
  EXPECT_EQ(outward.outcome, RayCastResult::Outcome::kMaxRange);
  EXPECT_EQ(map.castRay({30, 30, 30}, {1, 0, 0}, 5.0, false).outcome, RayCastResult::Outcome::kHitUnknown);
  EXPECT_EQ(map.castRay({0, 0, 0}, {0, 0, 0}, 5.0, false).outcome, RayCastResult::Outcome::kInvalid);

  // levels of detail: aligned, conservative for occupied cells, fewer cuboids
  for (int level : {1, 2, 4, 6}) {
    const auto coarse = map.levelOfDetail(level, lo, hi);
    EXPECT_LT(coarse.size(), map.stats().cuboids);
    std::unordered_map<BlockKey, float, BlockKeyHash> coarse_cell;  // coarse cell -> value
    for (const CuboidBox& c : coarse) {
      for (int a = 0; a < 3; ++a) {
        ASSERT_EQ(c.min[a] & ((1 << level) - 1), 0);
        ASSERT_EQ((c.max[a] + 1) & ((1 << level) - 1), 0);
      }
      for (int32_t z = c.min.z >> level; z <= c.max.z >> level; ++z) {
        for (int32_t y = c.min.y >> level; y <= c.max.y >> level; ++y) {
          for (int32_t x = c.min.x >> level; x <= c.max.x >> level; ++x) coarse_cell[{x, y, z}] = c.log_odds;
        }
      }
    }
    map.forEachKnownCell([&](const CellKey& c, float v) {
      const auto it = coarse_cell.find({c.x >> level, c.y >> level, c.z >> level});
      ASSERT_NE(it, coarse_cell.end());
      if (v >= 0.0f) {
        ASSERT_GE(it->second, 0.0f) << "a coarse cell over an occupied cell must be occupied";
      }
    });
  }
}

TEST(CuboidMap, PointQueryDoesNotRoundToFloatAtCellEdges) {
  // Near 3000 m floats are 0.24 mm apart: 2999.99999 rounds to 3000.0f, one cell too far.
  CuboidMap map(0.1);
  const float below_edge = std::nextafter(3000.0f, 0.0f);
  map.insertScan({2995.05f, 0.05f, 0.05f}, std::vector<Eigen::Vector3f>{{below_edge, 0.05f, 0.05f}});
  ASSERT_EQ(map.queryCell({29999, 0, 0}).state, CellState::kOccupied);
  ASSERT_EQ(map.queryCell({30000, 0, 0}).state, CellState::kUnknown);
  EXPECT_EQ(map.query({2999.99999, 0.05, 0.05}).state, CellState::kOccupied);
  EXPECT_EQ(map.query({3000.0, 0.05, 0.05}).state, CellState::kUnknown);
  // The inserted float point itself, widened to double, is found where the insert put it.
  EXPECT_EQ(map.query({double(below_edge), 0.05, 0.05}).cuboid.min.x, 29999);
  // Beyond the addressable range (and far beyond int32 cells) is unknown, also for boxes.
  EXPECT_EQ(map.query({3276.8, 0.0, 0.0}).state, CellState::kUnknown);
  EXPECT_EQ(map.query({-1e300, 0.0, 0.0}).state, CellState::kUnknown);
  const Eigen::AlignedBox3d everything(Eigen::Vector3d(-1e300, -1, -1), Eigen::Vector3d(1e300, 1, 1));
  EXPECT_FALSE(map.queryBox(everything).empty());
}

TEST(CuboidMap, BadScansThrowAndChangeNothing) {
  CuboidMap map(0.1);
  insertAll(map, roomScans(1, 9));
  const MapStats before = map.stats();
  const Eigen::Vector3f o(1, 1, 1);
  std::vector<Eigen::Vector3f> with_nan = {{2, 2, 2}, {NAN, 1, 1}};
  std::vector<Eigen::Vector3f> with_inf = {{2, 2, 2}, {1, INFINITY, 1}};
  std::vector<Eigen::Vector3f> far_away = {{2, 2, 2}, {1e6f, 0, 0}};
  EXPECT_THROW(map.insertScan(o, with_nan), std::invalid_argument);
  EXPECT_THROW(map.insertScan(o, with_inf), std::invalid_argument);
  EXPECT_THROW(map.insertScan(o, far_away), std::invalid_argument);
  EXPECT_THROW(map.insertScan(o, std::span<const Eigen::Vector3f>{}), std::invalid_argument);
  EXPECT_THROW(map.insertScan({NAN, 0, 0}, std::vector<Eigen::Vector3f>{{1, 1, 1}}), std::invalid_argument);
  EXPECT_THROW(map.insertScan(o, with_nan, {0, InvalidPoints::kReject}), std::invalid_argument);
  try {
    map.insertScan(o, with_nan);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("point 1"), std::string::npos) << e.what();
  }
  const MapStats after = map.stats();
  EXPECT_EQ(after.version, before.version);
  EXPECT_EQ(after.known_cells, before.known_cells);
  EXPECT_EQ(after.scans, before.scans);
  // skipping is explicit and counted
  const ScanStats s = map.insertScan(o, with_nan, {1, InvalidPoints::kSkip});
  EXPECT_EQ(s.rejected_points, 1u);
  EXPECT_THROW(CuboidMap(0.0), std::invalid_argument);
  EXPECT_THROW(CuboidMap(NAN), std::invalid_argument);
}

TEST(CuboidMap, ImportValidatesCuboids) {
  CuboidMap map(0.1);
  PackedCuboid inverted;
  inverted.lo_packed = PackedCuboid::pack(5, 0, 0);
  inverted.hi_packed = PackedCuboid::pack(2, 0, 0);
  PackedCuboid a, b;
  a.hi_packed = PackedCuboid::pack(3, 3, 3);
  b.lo_packed = PackedCuboid::pack(3, 3, 3);
  b.hi_packed = PackedCuboid::pack(4, 4, 4);
  EXPECT_THROW(map.replaceBlocks({{BlockKey{0, 0, 0}, {inverted}}}), std::invalid_argument);
  EXPECT_THROW(map.replaceBlocks({{BlockKey{0, 0, 0}, {a, b}}}), std::invalid_argument);  // overlap
  a.log_odds = NAN;
  EXPECT_THROW(map.replaceBlocks({{BlockKey{0, 0, 0}, {a}}}), std::invalid_argument);
  EXPECT_THROW(map.replaceBlocks({{BlockKey{5000, 0, 0}, {b}}}), std::invalid_argument);
  EXPECT_EQ(map.stats().blocks, 0u);
  const CuboidBox big{{-20, -20, -20}, {40, 3, 3}, -2.0f};
  map.setCuboids(std::span(&big, 1));
  EXPECT_EQ(map.stats().known_cells, uint64_t{61} * 24 * 24);
  EXPECT_EQ(map.queryCell({-20, 3, 3}).state, CellState::kFree);
  EXPECT_EQ(map.queryCell({41, 3, 3}).state, CellState::kUnknown);
}

TEST(CuboidMap, ReadersRunWhileOneWriterInserts) {
  const auto scans = roomScans(12, 11);
  CuboidMap map(0.1, {}, {0.25f, 1});
  std::atomic<bool> done{false};
  std::atomic<uint64_t> reads{0};
  std::vector<std::thread> readers;
  for (int r = 0; r < 2; ++r) {
    readers.emplace_back([&] {
      while (!done) {
        const CellQuery q = map.query({5.99, 2.5, 1.5});
        if (q.state != CellState::kUnknown) {
          EXPECT_TRUE(std::isfinite(q.log_odds));
        }
        map.queryBox(Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(6, 5, 3)), 50);
        map.castRay({3, 2.5, 1.5}, {1, 0.2, 0}, 10, true);
        reads += 3;
      }
    });
  }
  insertAll(map, scans);
  done = true;
  for (auto& t : readers) t.join();
  EXPECT_GT(reads.load(), 0u);
  CuboidMap sequential(0.1, {}, {0.25f, 1});
  insertAll(sequential, scans);
  EXPECT_EQ(map.stats().known_cells, sequential.stats().known_cells);
  EXPECT_EQ(map.stats().cuboids, sequential.stats().cuboids);
}

}  // namespace
}  // namespace rmap::map3d

namespace rmap::map3d {
namespace {

TEST(CuboidMapBlockVersions, OnlyBlocksTouchedByAScanCarryItsVersion) {
  CuboidMap map(0.1);
  const Eigen::Vector3f origin(0.05f, 0.05f, 0.05f);
  const std::vector<Eigen::Vector3f> near_points{{1.0f, 0.05f, 0.05f}};
  map.insertScan(origin, near_points);
  const uint64_t after_first = map.version();
  size_t blocks_first = 0;
  map.forEachBlockVersion([&](const BlockKey&, uint64_t v) {
    EXPECT_LE(v, after_first);
    ++blocks_first;
  });
  ASSERT_GT(blocks_first, 0u);

  // A scan far away (+x 8 m) touches new blocks only, plus the ray's path.
  const std::vector<Eigen::Vector3f> far_points{{0.05f, 8.0f, 0.05f}};
  map.insertScan(origin, far_points);
  std::vector<BlockKey> changed;
  map.forEachBlockVersion([&](const BlockKey& key, uint64_t v) {
    if (v > after_first) changed.push_back(key);
  });
  ASSERT_FALSE(changed.empty());
  bool reaches_far_end = false;
  for (const BlockKey& key : changed) {
    EXPECT_EQ(key.x, 0);  // the ray runs along +y in the first block column
    reaches_far_end |= key.y == blockOf(CellKey{0, 80, 0}).y;
  }
  EXPECT_TRUE(reaches_far_end);
}

}  // namespace
}  // namespace rmap::map3d

namespace rmap::map3d {
namespace {

TEST(CuboidMapRewrite, RewritesARowAndLeavesTheOtherCells) {
  CuboidMap map(0.1);
  // A horizontal ray at z index 5 and one at z index 8, from x cell 0 to 20.
  map.insertScan({0.05f, 0.05f, 0.55f}, std::vector<Eigen::Vector3f>{{2.05f, 0.05f, 0.55f}});
  map.insertScan({0.05f, 0.05f, 0.85f}, std::vector<Eigen::Vector3f>{{2.05f, 0.05f, 0.85f}});
  ASSERT_EQ(map.queryCell({20, 0, 5}).state, CellState::kOccupied);
  ASSERT_EQ(map.queryCell({3, 0, 5}).state, CellState::kFree);
  const uint64_t version = map.version();

  // Row z = 5 over x 0..31, y 0..3: a wall at x = 10, free before it, unknown beyond.
  map.rewriteCells({0, 0, 5}, {31, 3, 5}, [](const CellKey& c) -> std::optional<float> {
    if (c.x < 10) return -1.0f;
    if (c.x == 10) return 100.0f;  // clamped
    return std::nullopt;
  });
  EXPECT_GT(map.version(), version);
  EXPECT_EQ(map.queryCell({3, 0, 5}).state, CellState::kFree);
  EXPECT_FLOAT_EQ(map.queryCell({3, 0, 5}).log_odds, -1.0f);
  EXPECT_EQ(map.queryCell({10, 2, 5}).state, CellState::kOccupied);
  EXPECT_FLOAT_EQ(map.queryCell({10, 2, 5}).log_odds, map.occupancyParams().clamp_max_log_odds);
  EXPECT_EQ(map.queryCell({20, 0, 5}).state, CellState::kUnknown);  // the old wall is gone
  EXPECT_EQ(map.queryCell({15, 0, 5}).state, CellState::kUnknown);
  // The other row is untouched.
  EXPECT_EQ(map.queryCell({20, 0, 8}).state, CellState::kOccupied);
  EXPECT_EQ(map.queryCell({3, 0, 8}).state, CellState::kFree);
}

TEST(CuboidMapRewrite, UnknownOnlyRangesCreateNoBlocksAndBadInputChangesNothing) {
  CuboidMap map(0.1);
  map.insertScan({0.05f, 0.05f, 0.05f}, std::vector<Eigen::Vector3f>{{1.05f, 0.05f, 0.05f}});
  const MapStats before = map.stats();
  map.rewriteCells({1000, 1000, 0}, {1100, 1100, 0}, [](const CellKey&) { return std::nullopt; });
  EXPECT_EQ(map.stats().blocks, before.blocks);

  const uint64_t version = map.version();
  EXPECT_THROW(map.rewriteCells({5, 0, 0}, {4, 0, 0}, [](const CellKey&) { return 1.0f; }), std::invalid_argument);
  EXPECT_THROW(map.rewriteCells({0, 0, 0}, {kCellLimit, 0, 0}, [](const CellKey&) { return 1.0f; }),
               std::invalid_argument);
  EXPECT_THROW(map.rewriteCells({0, 0, 0}, {20, 0, 0},
                                [](const CellKey& c) { return c.x == 20 ? std::nanf("") : 1.0f; }),
               std::invalid_argument);
  EXPECT_EQ(map.version(), version);
  EXPECT_EQ(map.queryCell({3, 0, 0}).state, CellState::kFree);
  EXPECT_EQ(map.stats().known_cells, before.known_cells);
}

}  // namespace
}  // namespace rmap::map3d
