#include "slam2d/map_checkpoints.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace rmap::slam2d {
namespace {

constexpr double kResolution_m = 0.05;
constexpr int kLevels = 3;

/// Scan k of a robot driving along x in a 4 m wide corridor with a cross wall at x = 12 m:
/// rays every 2°, each ending on the first wall, with a reflectivity return at every endpoint.
void insertScan(GridMap2d& map, int k) {
  const Eigen::Vector2d origin(0.1 * k, 0.3 * std::sin(0.2 * k));
  std::vector<Ray> rays;
  for (int a = 0; a < 180; ++a) {
    const Eigen::Vector2d dir(std::cos(a * M_PI / 90.0), std::sin(a * M_PI / 90.0));
    double t = 30.0;
    if (dir.y() > 1e-9) t = std::min(t, (2.0 - origin.y()) / dir.y());
    if (dir.y() < -1e-9) t = std::min(t, (-2.0 - origin.y()) / dir.y());
    if (dir.x() > 1e-9) t = std::min(t, (12.0 - origin.x()) / dir.x());
    rays.push_back({origin + t * dir, t < 30.0});
  }
  map.insert(origin, rays, OccupancyUpdate{}, 25.0);
  for (const Ray& ray : rays)
    if (ray.hit) map.addReflectivity(ray.end_m, static_cast<float>(0.5 + 0.01 * (k % 7)));
}

GridMap2d render(int from, int to, GridMap2d map = GridMap2d(kResolution_m, kLevels)) {
  for (int k = from; k < to; ++k) insertScan(map, k);
  return map;
}

/// Every cell of every level (log-odds bit for bit, NaN alike) and the reflectivity layer agree.
void expectSameMaps(const GridMap2d& a, const GridMap2d& b) {
  for (int level = 0; level < kLevels; ++level) {
    const int step = 1 << level;
    for (int x = -20 / step; x < 300 / step; ++x)
      for (int y = -60 / step; y < 60 / step; ++y) {
        const float la = a.level(level).logOdds({x, y}), lb = b.level(level).logOdds({x, y});
        ASSERT_TRUE((std::isnan(la) && std::isnan(lb)) || la == lb) << level << ": " << x << ", " << y;
      }
  }
  for (int x = -20; x < 300; ++x)
    for (int y = -60; y < 60; ++y) {
      ASSERT_EQ(a.reflectivity({x, y}).count, b.reflectivity({x, y}).count) << x << ", " << y;
      ASSERT_EQ(a.reflectivity({x, y}).mean, b.reflectivity({x, y}).mean) << x << ", " << y;
    }
}

TEST(MapCheckpoints, KeepsCopiesOnTheSpacingAndThinsThemWhenTooMany) {
  MapCheckpoints checkpoints(4);
  const GridMap2d map(kResolution_m, kLevels);
  for (size_t k = 1; k <= 40; ++k) checkpoints.offer(k, map);
  // 8, 16, 24, 32 fill it; 40 doubles the spacing: 16 and 32 stay, 40 is off it.
  EXPECT_EQ(checkpoints.spacing(), 16u);
  EXPECT_EQ(checkpoints.size(), 2u);
  ASSERT_NE(checkpoints.latestUpTo(40), nullptr);
  EXPECT_EQ(checkpoints.latestUpTo(40)->keyframes, 32u);
  EXPECT_EQ(checkpoints.latestUpTo(31)->keyframes, 16u) << "the copy of 32 keyframes holds one that moved";
  EXPECT_EQ(checkpoints.size(), 1u) << "copies past the moved keyframe are dropped";
  EXPECT_EQ(checkpoints.latestUpTo(15), nullptr);
  checkpoints.offer(16, map);
  checkpoints.offer(48, map);
  EXPECT_EQ(checkpoints.latestUpTo(100)->keyframes, 48u);
  checkpoints.clear();
  EXPECT_EQ(checkpoints.latestUpTo(100), nullptr);
}

TEST(MapCheckpoints, NoneAreKeptWhenOff) {
  MapCheckpoints off(0);
  for (size_t k = 1; k <= 64; ++k) off.offer(k, GridMap2d(kResolution_m, kLevels));
  EXPECT_EQ(off.size(), 0u);
  EXPECT_EQ(off.latestUpTo(64), nullptr);
}

TEST(MapCheckpoints, RenderingOnFromACopyGivesTheMapRenderedFromTheStart) {
  const int scans = 60;
  const GridMap2d from_start = render(0, scans);
  // The live map, offered after every scan; later scans write chunks the copies share.
  MapCheckpoints checkpoints(3);
  GridMap2d live(kResolution_m, kLevels);
  for (int k = 0; k < scans; ++k) {
    insertScan(live, k);
    checkpoints.offer(static_cast<size_t>(k + 1), live);
  }
  expectSameMaps(live, from_start);
  // Scan 41 moved: start from the copy before it (32 scans, spacing 16 by now).
  const MapCheckpoints::Checkpoint* checkpoint = checkpoints.latestUpTo(41);
  ASSERT_NE(checkpoint, nullptr);
  EXPECT_EQ(checkpoint->keyframes, 32u);
  expectSameMaps(checkpoint->map, render(0, 32));
  const GridMap2d resumed = render(32, scans, checkpoint->map);
  expectSameMaps(resumed, from_start);
  // Writing on from the copy changed neither the copy nor the live map.
  expectSameMaps(checkpoint->map, render(0, 32));
  expectSameMaps(live, from_start);
}

TEST(MapCheckpoints, CopiesNeverHoldMoreChunksOfTheirOwnThanTheMap) {
  // A robot driving the same 6 m of corridor to and fro: every scan rewrites the chunks of the
  // last copies, so each copy soon holds a whole map of its own.
  MapCheckpoints checkpoints(16);
  GridMap2d live(kResolution_m, kLevels);
  size_t most = 0;
  for (int k = 0; k < 400; ++k) {
    insertScan(live, (k / 60) % 2 == 0 ? k % 60 : 59 - k % 60);
    checkpoints.offer(static_cast<size_t>(k + 1), live);
    size_t map_chunks = 0;
    live.forEachChunk([&](const void*) { ++map_chunks; });
    // The bound holds as a copy is taken; until the next one the map's writes add at most itself.
    ASSERT_LE(checkpoints.chunksOfTheirOwn(live), (MapCheckpoints::kMaxOwnChunksPerMapChunk + 1) * map_chunks)
        << "scan " << k;
    most = std::max(most, checkpoints.size());
  }
  EXPECT_GE(most, 2u);  // (without the bound the copies' own chunks pass 5 maps by scan 400)
  // What is left still renders on to the map rendered from the start.
  const MapCheckpoints::Checkpoint* checkpoint = checkpoints.latestUpTo(400);
  ASSERT_NE(checkpoint, nullptr);
  GridMap2d resumed = checkpoint->map;
  for (int k = static_cast<int>(checkpoint->keyframes); k < 400; ++k)
    insertScan(resumed, (k / 60) % 2 == 0 ? k % 60 : 59 - k % 60);
  expectSameMaps(resumed, live);
}

}  // namespace
}  // namespace rmap::slam2d
