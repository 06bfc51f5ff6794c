#include "map3d/map_file.h"

#include <gtest/gtest.h>

#include <random>

namespace rmap::map3d {
namespace {

std::unique_ptr<CuboidMap> sampleMap() {
  auto map = std::make_unique<CuboidMap>(0.1);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-4.0f, 4.0f);
  for (int s = 0; s < 3; ++s) {
    std::vector<Eigen::Vector3f> points;
    for (int i = 0; i < 2000; ++i) points.push_back({u(rng), u(rng), u(rng) * 0.5f});
    map->insertScan({0.1f * s, 0.0f, 0.0f}, points);
  }
  return map;
}

TEST(MapFile, RoundTripKeepsEveryCellAndParameter) {
  const auto map = sampleMap();
  const std::string bytes = encodeMap(*map);
  const auto back = decodeMap(bytes);
  EXPECT_EQ(back->resolution(), map->resolution());
  EXPECT_EQ(back->fusionParams().tolerance_log_odds, map->fusionParams().tolerance_log_odds);
  EXPECT_EQ(back->stats().known_cells, map->stats().known_cells);
  map->forEachKnownCell([&](const CellKey& c, float v) {
    const CellQuery q = back->queryCell(c);
    ASSERT_NE(q.state, CellState::kUnknown);
    // hot blocks are written fused, so values move by at most half the tolerance
    ASSERT_NEAR(q.log_odds, v, map->fusionParams().tolerance_log_odds / 2 + 1e-6);
  });
  // compact: about 8 bytes per cuboid plus 16 per block
  const MapStats s = back->stats();
  EXPECT_LE(bytes.size(), 100 + s.cuboids * 8 + s.blocks * 16);
  EXPECT_EQ(encodeMap(*back), encodeMap(*back));
}

TEST(MapFile, EmptyMapRoundTrips) {
  CuboidMap empty(0.2);
  EXPECT_EQ(decodeMap(encodeMap(empty))->stats().blocks, 0u);
}

TEST(MapFile, CorruptOrTruncatedFilesAreRejected) {
  const std::string bytes = encodeMap(*sampleMap());
  EXPECT_THROW(decodeMap(""), std::runtime_error);
  EXPECT_THROW(decodeMap("hello world, not a map"), std::runtime_error);
  for (size_t cut : {size_t{9}, size_t{40}, bytes.size() / 2, bytes.size() - 1}) {
    EXPECT_THROW(decodeMap(std::string_view(bytes).substr(0, cut)), std::runtime_error) << "cut at " << cut;
  }
  std::string flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x10;
  try {
    decodeMap(flipped);
    FAIL() << "a flipped bit must be detected";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("CRC"), std::string::npos) << e.what();
  }
  EXPECT_THROW(decodeMap(bytes + "x"), std::runtime_error);
}

}  // namespace
}  // namespace rmap::map3d
