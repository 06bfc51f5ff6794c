#pragma once
/// @file metrics_sampler.h
/// Reading rmapd's /metrics (Prometheus text): one value, or the largest
/// values of some gauges sampled while a load runs.

#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace rmap::client {

/// Value of an unlabelled metric (`name value` line) in Prometheus text, -1 when absent.
double prometheusValue(const std::string& text, const std::string& name);

/// Quantile q (0..1) of a Prometheus histogram `name` (its `_bucket{le=…}` and `_count`
/// lines): the smallest bucket bound holding that share of the observations, +inf when only
/// the +Inf bucket does, -1 when the histogram is absent or empty.
double prometheusQuantile(const std::string& text, const std::string& name, double q);

/// Polls GET /metrics on its own thread and keeps the latest and the largest
/// value of each named metric; a failed poll is skipped (the next one counts).
class MetricsSampler {
 public:
  /// @param http_url  http://host:port; `token` needs the admin role unless loopback-only
  MetricsSampler(const std::string& http_url, const std::string& token, std::vector<std::string> names,
                 std::chrono::milliseconds period = std::chrono::milliseconds(200));
  ~MetricsSampler();  ///< stops
  MetricsSampler(const MetricsSampler&) = delete;
  MetricsSampler& operator=(const MetricsSampler&) = delete;

  void stop();
  /// Largest value of `name` seen so far; -1 before a poll found it.
  double max(const std::string& name) const;
  /// Value of `name` in the latest poll that answered; -1 before one found it.
  double latest(const std::string& name) const;
  /// Polls that answered.
  uint64_t samples() const { return samples_.load(); }

 private:
  const std::vector<std::string> names_;
  std::atomic<bool> stop_{false};
  std::atomic<uint64_t> samples_{0};
  mutable std::mutex mutex_;
  std::map<std::string, double> max_;     ///< guarded by mutex_
  std::map<std::string, double> latest_;  ///< guarded by mutex_
  std::thread thread_;
};

}  // namespace rmap::client
