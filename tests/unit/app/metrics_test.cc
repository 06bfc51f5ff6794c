#include "app/metrics.h"

#include "app/loop_closures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace rmap::app {
namespace {

bool hasLine(const std::string& text, const std::string& line) {
  return ("\n" + text).find("\n" + line + "\n") != std::string::npos;
}

/// 0.25 s once, 0.5 s twice and 20 s once: exact in binary, so the sum is too.
void observeSample(LatencyHistogram& histogram) {
  for (const double s : {0.25, 0.5, 0.5, 20.0}) histogram.observe(s);
}

TEST(LatencyHistogram, EmptyQuantileIsZero) {
  const LatencyHistogram histogram;
  EXPECT_EQ(histogram.quantile(0.5), 0.0);
}

TEST(LatencyHistogram, QuantileIsTheUpperBoundOfItsBucket) {
  LatencyHistogram histogram;
  observeSample(histogram);
  EXPECT_EQ(histogram.quantile(0.25), 0.25);
  EXPECT_EQ(histogram.quantile(0.5), 0.5);
  EXPECT_EQ(histogram.quantile(0.75), 0.5);
  EXPECT_TRUE(std::isinf(histogram.quantile(1.0)));
}

TEST(LatencyHistogram, SmallValuesFallInTheFirstBucket) {
  LatencyHistogram histogram;
  histogram.observe(0.0001);
  histogram.observe(0.0005);
  histogram.observe(0.0007);
  EXPECT_EQ(histogram.quantile(0.6), 0.0005);
  EXPECT_EQ(histogram.quantile(1.0), 0.001);
}

TEST(LatencyHistogram, RendersCumulativeBucketsSumAndCount) {
  LatencyHistogram histogram;
  observeSample(histogram);
  std::string out;
  histogram.render("rmap_test_seconds", "A test histogram.", out);

  EXPECT_TRUE(hasLine(out, "# HELP rmap_test_seconds A test histogram.")) << out;
  EXPECT_TRUE(hasLine(out, "# TYPE rmap_test_seconds histogram")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_test_seconds_bucket{le=\"0.0005\"} 0")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_test_seconds_bucket{le=\"0.1\"} 0")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_test_seconds_bucket{le=\"0.25\"} 1")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_test_seconds_bucket{le=\"0.5\"} 3")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_test_seconds_bucket{le=\"10\"} 3")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_test_seconds_bucket{le=\"+Inf\"} 4")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_test_seconds_sum 21.250000000")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_test_seconds_count 4")) << out;
}

TEST(LatencyHistogram, RendersOneBucketLinePerBoundPlusInf) {
  const LatencyHistogram histogram;
  std::string out;
  histogram.render("h", "help", out);
  size_t buckets = 0;
  for (size_t at = out.find("h_bucket{"); at != std::string::npos; at = out.find("h_bucket{", at + 1)) ++buckets;
  EXPECT_EQ(buckets, LatencyHistogram::kBoundsS.size() + 1);
  EXPECT_TRUE(hasLine(out, "h_count 0")) << out;
}

TEST(RenderPrometheus, CountersHaveHelpTypeAndValue) {
  Metrics metrics;
  metrics.messages_acked = 17;
  metrics.messages_durable = 12;
  metrics.viewer_frames_dropped = 3;
  const std::string out = renderPrometheus(metrics, MetricsGauges{});

  EXPECT_TRUE(hasLine(out, "# TYPE rmap_messages_acked_total counter")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_messages_acked_total 17")) << out;
  EXPECT_TRUE(hasLine(out, "# TYPE rmap_messages_durable_total counter")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_messages_durable_total 12")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_viewer_frames_dropped_total 3")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_messages_received_total 0")) << out;
  EXPECT_NE(out.find("# HELP rmap_messages_acked_total "), std::string::npos);
  EXPECT_NE(out.find("# HELP rmap_messages_durable_total "), std::string::npos);
}

TEST(RenderPrometheus, GaugesHaveTypeGaugeAndValue) {
  MetricsGauges gauges;
  gauges.robot_connections = 2;
  gauges.maps = 5;
  gauges.map_memory_bytes = 123456789;
  const std::string out = renderPrometheus(Metrics{}, gauges);
  EXPECT_TRUE(hasLine(out, "# TYPE rmap_robot_connections gauge")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_robot_connections 2")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_maps 5")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_map_memory_bytes 123456789")) << out;
}

TEST(RenderPrometheus, ReportsMemoryAndViewerBacklog) {
  Metrics metrics;
  metrics.messages_refused_memory = 4;
  metrics.imports_refused_memory = 1;
  MetricsGauges gauges;
  gauges.resident_memory_bytes = 100u << 20;
  gauges.resident_memory_peak_bytes = 120u << 20;
  gauges.memory_bound_bytes = 512u << 20;
  gauges.viewers_skipping = 3;
  gauges.viewer_queue_bytes = 65536;
  const std::string out = renderPrometheus(metrics, gauges);
  EXPECT_TRUE(hasLine(out, "rmap_messages_refused_memory_total 4")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_imports_refused_memory_total 1")) << out;
  EXPECT_TRUE(hasLine(out, "# TYPE rmap_resident_memory_bytes gauge")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_resident_memory_bytes 104857600")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_resident_memory_peak_bytes 125829120")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_memory_bound_bytes 536870912")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_viewers_skipping 3")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_viewer_queue_bytes 65536")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_viewer_tick_seconds_count 0")) << out;
}

TEST(RenderPrometheus, IncludesTheLatencyHistograms) {
  Metrics metrics;
  metrics.ack_latency.observe(0.00390625);  // 2^-8 s: exact in nanoseconds
  const std::string out = renderPrometheus(metrics, MetricsGauges{});
  EXPECT_TRUE(hasLine(out, "# TYPE rmap_ack_latency_seconds histogram")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_ack_latency_seconds_bucket{le=\"0.0025\"} 0")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_ack_latency_seconds_bucket{le=\"0.005\"} 1")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_ack_latency_seconds_count 1")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_apply_latency_seconds_count 0")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_http_request_seconds_count 0")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_ack_latency_seconds_sum 0.003906250")) << out;
}

TEST(RenderPrometheus, LoopClosuresAreCountedBySource) {
  Metrics m;
  m.loop_closures[static_cast<size_t>(LoopSource::kGeometry)] = 3;
  m.loop_closures[static_cast<size_t>(LoopSource::kCamera)] = 1;
  const std::string out = renderPrometheus(m, MetricsGauges{});
  EXPECT_TRUE(hasLine(out, "# TYPE rmap_loop_closures_total counter")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_loop_closures_total{source=\"camera\"} 1")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_loop_closures_total{source=\"laser_intensity\"} 0")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_loop_closures_total{source=\"geometry\"} 3")) << out;
  EXPECT_TRUE(hasLine(out, "rmap_loop_closures_refused_total 0")) << out;
}

TEST(RenderPrometheus, EveryMetricHasOneHelpAndOneTypeLine) {
  const std::string out = renderPrometheus(Metrics{}, MetricsGauges{});
  size_t help = 0, type = 0;
  for (size_t at = out.find("# HELP "); at != std::string::npos; at = out.find("# HELP ", at + 1)) ++help;
  for (size_t at = out.find("# TYPE "); at != std::string::npos; at = out.find("# TYPE ", at + 1)) ++type;
  EXPECT_EQ(help, type);
  EXPECT_EQ(help, 25u + 15u + 7u);  // counters, gauges, histograms
}

}  // namespace
}  // namespace rmap::app
