#include "loop_sim/loop_sim_bench.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace rmap::bench {
namespace {

TEST(LoopSimBench, ParsesProjectionNames) {
  EXPECT_EQ(projectionFromString("equirectangular"), loop::PanoramaProjection::kEquirectangular);
  EXPECT_EQ(projectionFromString("ring"), loop::PanoramaProjection::kRingByColumn);
  EXPECT_THROW(projectionFromString("spherical-ish"), std::invalid_argument);
}

TEST(LoopSimBench, RejectsAnUnknownModality) {
  LoopSimBenchOptions o;
  o.modality = "sonar";
  EXPECT_THROW(runLoopSimBench(o), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::bench
