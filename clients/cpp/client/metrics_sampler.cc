#include "client/metrics_sampler.h"

#include <algorithm>
#include <cmath>

#include "client/http_client.h"
#include "client/robot_client.h"

namespace rmap::client {

double prometheusValue(const std::string& text, const std::string& name) {
  const std::string key = name + " ";
  for (size_t at = text.find(key); at != std::string::npos; at = text.find(key, at + 1)) {
    if (at == 0 || text[at - 1] == '\n') return std::stod(text.substr(at + key.size()));
  }
  return -1.0;
}

double prometheusQuantile(const std::string& text, const std::string& name, double q) {
  const double count = prometheusValue(text, name + "_count");
  if (count <= 0) return -1.0;
  const std::string prefix = name + "_bucket{le=\"";
  for (size_t at = text.find(prefix); at != std::string::npos; at = text.find(prefix, at + 1)) {
    if (at != 0 && text[at - 1] != '\n') continue;
    const size_t bound_end = text.find("\"} ", at + prefix.size());
    if (bound_end == std::string::npos) break;
    const std::string bound = text.substr(at + prefix.size(), bound_end - at - prefix.size());
    if (std::stod(text.substr(bound_end + 3)) >= q * count) return bound == "+Inf" ? INFINITY : std::stod(bound);
  }
  return INFINITY;
}

MetricsSampler::MetricsSampler(const std::string& http_url, const std::string& token, std::vector<std::string> names,
                               std::chrono::milliseconds period)
    : names_(std::move(names)) {
  for (const std::string& name : names_) max_[name] = latest_[name] = -1.0;
  Endpoint::parse(http_url);  // a bad URL throws here, not on the thread
  thread_ = std::thread([this, http_url, token, period] {
    HttpClient http(http_url, token);
    while (!stop_) {
      try {
        const HttpResponse response = http.get("/metrics");
        if (response.status == 200) {
          ++samples_;
          std::lock_guard lock(mutex_);
          for (const std::string& name : names_) {
            latest_[name] = prometheusValue(response.body, name);
            max_[name] = std::max(max_[name], latest_[name]);
          }
        }
      } catch (const ClientError&) {
        // a poll lost under load
      }
      std::this_thread::sleep_for(period);
    }
  });
}

MetricsSampler::~MetricsSampler() { stop(); }

void MetricsSampler::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

double MetricsSampler::max(const std::string& name) const {
  std::lock_guard lock(mutex_);
  const auto it = max_.find(name);
  return it == max_.end() ? -1.0 : it->second;
}

double MetricsSampler::latest(const std::string& name) const {
  std::lock_guard lock(mutex_);
  const auto it = latest_.find(name);
  return it == latest_.end() ? -1.0 : it->second;
}

}  // namespace rmap::client
