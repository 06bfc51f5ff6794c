// QueryLoad: a thread per keep-alive connection, each cycling over the targets.

#include "client/query_load.h"

#include <atomic>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "client/http_client.h"
#include "client/robot_client.h"

namespace rmap::client {

namespace {
using Clock = std::chrono::steady_clock;
constexpr size_t kErrorsKept = 10;
}  // namespace

struct QueryLoad::Impl {
  explicit Impl(QueryLoadOptions o) : options(std::move(o)) {}

  void run(int connection) {
    QueryLoadResult mine;
    HttpClient http(options.server_url, options.token, options.timeout);
    for (size_t i = static_cast<size_t>(connection); !stopping.load(std::memory_order_relaxed); ++i) {
      const std::string& target = options.targets[i % options.targets.size()];
      const auto sent = Clock::now();
      try {
        const HttpResponse response = http.get(target);
        mine.latencies_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - sent).count());
        ++mine.statuses[response.status];
        ++mine.answered;
      } catch (const ClientError& e) {
        ++mine.failed;
        if (mine.first_errors.size() < kErrorsKept) mine.first_errors.push_back(target + ": " + e.what());
      }
      if (options.pause.count() > 0) std::this_thread::sleep_for(options.pause);
    }
    std::lock_guard lock(mutex);
    total.answered += mine.answered;
    total.failed += mine.failed;
    for (const auto& [status, count] : mine.statuses) total.statuses[status] += count;
    total.latencies_ms.insert(total.latencies_ms.end(), mine.latencies_ms.begin(), mine.latencies_ms.end());
    for (std::string& e : mine.first_errors) {
      if (total.first_errors.size() < kErrorsKept) total.first_errors.push_back(std::move(e));
    }
  }

  QueryLoadOptions options;
  std::atomic<bool> stopping{false};
  Clock::time_point start = Clock::now();
  std::vector<std::thread> threads;
  std::mutex mutex;
  QueryLoadResult total;  ///< guarded by mutex
};

QueryLoad::QueryLoad(QueryLoadOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {
  if (impl_->options.targets.empty()) throw std::invalid_argument("a query load needs at least one target");
  if (impl_->options.connections < 1) throw std::invalid_argument("a query load needs at least one connection");
  // HttpClient's constructor only parses the URL (it connects on the first request): check it here.
  Endpoint::parse(impl_->options.server_url);
  for (int c = 0; c < impl_->options.connections; ++c) impl_->threads.emplace_back([this, c] { impl_->run(c); });
}

QueryLoad::~QueryLoad() {
  if (!impl_->threads.empty()) stop();
}

QueryLoadResult QueryLoad::stop() {
  impl_->stopping = true;
  for (std::thread& t : impl_->threads) t.join();
  impl_->threads.clear();
  QueryLoadResult result = std::move(impl_->total);
  result.wall_s = std::chrono::duration<double>(Clock::now() - impl_->start).count();
  return result;
}

}  // namespace rmap::client
