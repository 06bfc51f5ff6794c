#include "map3d/scan_update.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <tuple>

namespace rmap::map3d {
namespace {

std::vector<Eigen::Vector3f> randomPoints(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-8.0f, 8.0f);
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < n; ++i) points.push_back({u(rng), u(rng), u(rng) * 0.3f});
  return points;
}

TEST(ScanUpdate, MarksAreDisjointAfterResolve) {
  const Grid grid(0.1);
  ScanUpdate update;
  update.gather(grid, OccupancyParams{}, {0.3f, 0.2f, 0.1f}, randomPoints(2000, 1));
  update.resolve();
  uint64_t occupied = 0;
  for (const BlockMarks& m : update.blocks()) {
    for (int w = 0; w < kBlockWords; ++w) EXPECT_EQ(m.free.words[w] & m.occupied.words[w], 0u);
    occupied += m.occupied.count();
  }
  EXPECT_EQ(occupied, update.stats().occupied_cells);
  EXPECT_GT(update.stats().free_cells, update.stats().occupied_cells);
}

TEST(ScanUpdate, MergedPartsEqualOneGather) {
  const Grid grid(0.05);
  const auto points = randomPoints(5000, 2);
  const Eigen::Vector3f origin(0.0f, 0.0f, 0.5f);
  OccupancyParams exact;
  exact.free_space_tracing = FreeSpaceTracing::kOctomapExact;
  ScanUpdate whole;
  whole.gather(grid, exact, origin, points);
  whole.resolve();
  ScanUpdate a, b;
  a.gather(grid, exact, origin, std::span(points).first(1234));
  b.gather(grid, exact, origin, std::span(points).subspan(1234));
  a.merge(std::move(b));
  a.resolve();
  EXPECT_EQ(a.stats().points, whole.stats().points);
  EXPECT_EQ(a.stats().occupied_cells, whole.stats().occupied_cells);
  EXPECT_EQ(a.stats().free_cells, whole.stats().free_cells);
  ASSERT_EQ(a.blocks().size(), whole.blocks().size());
}

TEST(ScanUpdate, CountsRejectedPointsAndTruncatedRays) {
  const Grid grid(0.5);
  OccupancyParams params;
  params.max_range_m = 2.25;
  ScanUpdate update;
  const std::vector<Eigen::Vector3f> points = {{1.25f, 0, 0}, {5, 0, 0}, {NAN, 0, 0}, {1e7f, 0, 0}};
  update.gather(grid, params, {0.1f, 0, 0}, points);
  update.resolve();
  EXPECT_EQ(update.stats().points, 4u);
  EXPECT_EQ(update.stats().rejected_points, 2u);
  EXPECT_EQ(update.stats().max_range_rays, 1u);
  EXPECT_EQ(update.stats().occupied_cells, 1u);
  // free: cells 0, 1 and 3 (up to the truncated end in cell 4); cell 2 holds the endpoint
  EXPECT_EQ(update.stats().free_cells, 3u);
}

// A ray alone in its scan never meets cells freed before, so the backward walk
// runs from its end to the sensor: it frees a 6-connected path from the
// sensor's cell to a neighbour of the end cell, one cell per unit of their
// Manhattan distance, and almost always OctoMap's cells exactly (only
// near-ties of cell borders can round the other way).
TEST(ScanUpdate, BackwardWalkFreesTheWholeLoneRay) {
  const Grid grid(0.1);
  OccupancyParams exact_params;
  exact_params.free_space_tracing = FreeSpaceTracing::kOctomapExact;
  const Eigen::Vector3f origin(0.33f, -0.71f, 1.02f);
  CellKey origin_cell;
  ASSERT_TRUE(grid.cellChecked(origin, origin_cell));
  auto freeCells = [&](const OccupancyParams& params, const Eigen::Vector3f& end) {
    ScanUpdate update;
    const std::vector<Eigen::Vector3f> points = {end};
    update.gather(grid, params, origin, points);
    update.resolve();
    std::vector<CellKey> cells;
    for (const BlockMarks& m : update.blocks()) m.free.forEach([&](int i) { cells.push_back(cellOf(m.key, i)); });
    std::sort(cells.begin(), cells.end(), [](const CellKey& a, const CellKey& b) {
      return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
    });
    return cells;
  };
  const auto ends = randomPoints(500, 3);
  int same_as_exact = 0;
  for (const Eigen::Vector3f& end : ends) {
    CellKey end_cell;
    ASSERT_TRUE(grid.cellChecked(end, end_cell));
    const std::vector<CellKey> cells = freeCells(OccupancyParams{}, end);
    const int distance = std::abs(end_cell.x - origin_cell.x) + std::abs(end_cell.y - origin_cell.y) +
                         std::abs(end_cell.z - origin_cell.z);
    ASSERT_EQ(static_cast<int>(cells.size()), distance);
    // the path: each cell's distance to the end cell is one less than the one before, ending next to the end cell
    std::vector<int> to_end;
    for (const CellKey& c : cells) {
      to_end.push_back(std::abs(c.x - end_cell.x) + std::abs(c.y - end_cell.y) + std::abs(c.z - end_cell.z));
    }
    std::sort(to_end.begin(), to_end.end());
    for (int k = 0; k < distance; ++k) ASSERT_EQ(to_end[k], k + 1);
    EXPECT_NE(std::find(cells.begin(), cells.end(), origin_cell), cells.end());
    same_as_exact += cells == freeCells(exact_params, end);
  }
  EXPECT_GE(same_as_exact, 495);
}

}  // namespace
}  // namespace rmap::map3d
