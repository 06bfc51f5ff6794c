#include "client/metrics_sampler.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace rmap::client {
namespace {

constexpr const char* kText =
    "# HELP rmap_viewers_skipping Viewers too far behind whose frames are being skipped.\n"
    "# TYPE rmap_viewers_skipping gauge\n"
    "rmap_viewers_skipping 8\n"
    "rmap_viewers_skipping_extra 3\n"
    "rmap_ack_latency_seconds_bucket{le=\"2.5\"} 3589\n"
    "rmap_ack_latency_seconds_count 3600\n";

TEST(PrometheusValue, ReadsTheLineOfTheNameNotItsHelpNorLongerNames) {
  EXPECT_EQ(prometheusValue(kText, "rmap_viewers_skipping"), 8.0);
  EXPECT_EQ(prometheusValue(kText, "rmap_viewers_skipping_extra"), 3.0);
  EXPECT_EQ(prometheusValue(kText, "rmap_ack_latency_seconds_count"), 3600.0);
}

TEST(PrometheusValue, ReadsALabelledSeriesGivenWholeAndMissesAbsentOnes) {
  EXPECT_EQ(prometheusValue(kText, "rmap_ack_latency_seconds_bucket{le=\"2.5\"}"), 3589.0);
  EXPECT_EQ(prometheusValue(kText, "rmap_ack_latency_seconds_bucket{le=\"5\"}"), -1.0);
  EXPECT_EQ(prometheusValue(kText, "rmap_ack_latency_seconds"), -1.0);
  EXPECT_EQ(prometheusValue("", "rmap_viewers_skipping"), -1.0);
}

TEST(PrometheusValue, TheFirstLineCounts) {
  EXPECT_EQ(prometheusValue("rmap_maps 2\nrmap_map_cuboids 7\n", "rmap_maps"), 2.0);
}

TEST(PrometheusQuantile, IsTheFirstBucketBoundHoldingTheShare) {
  const std::string text =
      "rmap_tick_seconds_bucket{le=\"0.1\"} 50\n"
      "rmap_tick_seconds_bucket{le=\"0.5\"} 99\n"
      "rmap_tick_seconds_bucket{le=\"+Inf\"} 100\n"
      "rmap_tick_seconds_sum 20.5\n"
      "rmap_tick_seconds_count 100\n";
  EXPECT_EQ(prometheusQuantile(text, "rmap_tick_seconds", 0.5), 0.1);
  EXPECT_EQ(prometheusQuantile(text, "rmap_tick_seconds", 0.51), 0.5);
  EXPECT_EQ(prometheusQuantile(text, "rmap_tick_seconds", 0.99), 0.5);
  EXPECT_TRUE(std::isinf(prometheusQuantile(text, "rmap_tick_seconds", 1.0)));
  EXPECT_EQ(prometheusQuantile(text, "rmap_other_seconds", 0.5), -1.0);
  EXPECT_EQ(prometheusQuantile("rmap_tick_seconds_count 0\n", "rmap_tick_seconds", 0.5), -1.0);
}

}  // namespace
}  // namespace rmap::client
