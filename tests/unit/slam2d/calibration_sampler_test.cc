#include "slam2d/calibration_sampler.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rmap::slam2d {
namespace {

TEST(CalibrationSampler, KeepsOnlyDistinctViewsOfACell) {
  CalibrationSampler sampler;
  for (int i = 0; i < 10; ++i) sampler.add(1, 2.0f, 0.9f, 100.0f);  // a robot standing still
  EXPECT_EQ(sampler.observations().size(), 1u);
  sampler.add(1, 2.05f, 0.9f, 100.0f);  // 2.5 % farther: same view
  sampler.add(1, 2.2f, 0.9f, 90.0f);    // 10 % farther: new
  sampler.add(1, 2.2f, 0.8f, 80.0f);    // 8° more oblique: new
  EXPECT_EQ(sampler.observations().size(), 3u);
  EXPECT_EQ(sampler.observations()[1].range_m, 2.2f);
  // Unusable readings are ignored.
  sampler.add(2, -1.0f, 0.9f, 10.0f);
  sampler.add(2, 1.0f, 0.0f, 10.0f);
  sampler.add(2, 1.0f, 0.9f, 0.0f);
  sampler.add(2, 1.0f, 0.9f, std::nanf(""));
  EXPECT_EQ(sampler.observations().size(), 3u);
}

TEST(CalibrationSampler, IsReadyWhenEnoughCellsWereSeenFromVariedRangesAndBounded) {
  CalibrationSamplerOptions options;
  options.min_well_seen_cells = 50;
  options.min_observations = 200;
  options.max_observations = 1000;
  options.max_views_per_cell = 5;
  CalibrationSampler sampler(options);
  // 100 cells seen from one range only: never "well seen".
  for (uint64_t c = 0; c < 100; ++c)
    for (int v = 0; v < 5; ++v) sampler.add(c, 3.0f, 0.95f - 0.001f * v, 50.0f);
  EXPECT_FALSE(sampler.ready());
  // 60 cells seen at 1, 1.5 and 2.25 m: ranges spanning more than 30 %.
  for (uint64_t c = 100; c < 160; ++c)
    for (float r : {1.0f, 1.5f, 2.25f, 3.0f}) sampler.add(c, r, 0.9f, 100.0f / r);
  EXPECT_TRUE(sampler.ready());
  sampler.postpone();  // a failed fit doubles the cells needed
  EXPECT_FALSE(sampler.ready());
  // The bound holds however much is offered; a cell takes at most max_views_per_cell.
  for (uint64_t c = 200; c < 2000; ++c)
    for (float r : {1.0f, 2.0f, 4.0f, 8.0f, 16.0f, 32.0f, 64.0f}) sampler.add(c, r, 0.9f, 10.0f);
  EXPECT_TRUE(sampler.full());
  EXPECT_EQ(sampler.observations().size(), options.max_observations);
  size_t views_of_200 = 0;
  for (const IntensityObservation& o : sampler.observations()) views_of_200 += o.cell_id == 200;
  EXPECT_EQ(views_of_200, 5u);
}

}  // namespace
}  // namespace rmap::slam2d
