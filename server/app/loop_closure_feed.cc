#include "app/loop_closure_feed.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <stdexcept>

namespace rmap::app {

LoopClosureFeed::LoopClosureFeed(std::string map, const RecognizerFactory& factory, LoopClosureSink sink,
                                 Metrics& metrics, size_t max_queued)
    : map_(std::move(map)), sink_(std::move(sink)), metrics_(metrics), max_queued_(max_queued) {
  if (max_queued_ < 1) throw std::invalid_argument("loop closure feed: max_queued must be >= 1");
  if (factory) {
    for (FrameKind kind : kFrameKinds) {
      if (std::unique_ptr<PlaceRecognizer> r = factory(kind)) recognizers_.emplace(kind, Recognizer{std::move(r), {}});
    }
  }
  thread_ = std::thread([this] { run(); });
}

LoopClosureFeed::~LoopClosureFeed() { stop(); }

bool LoopClosureFeed::push(Frame frame, bool wait) {
  if (!accepts(frame.kind)) throw std::invalid_argument("loop closure feed: no recognizer for this kind of frame");
  std::unique_lock lock(mutex_);
  if (!wait && queued_frames_ >= max_queued_) {
    metrics_.loop_frames_dropped.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  changed_.wait(lock, [&] { return queued_frames_ < max_queued_ || stopping_; });
  if (stopping_) return false;
  queue_.emplace_back(std::move(frame));
  ++queued_frames_;
  changed_.notify_all();
  return true;
}

void LoopClosureFeed::post(LoopClosure closure) {
  std::lock_guard lock(mutex_);
  if (stopping_) return;
  queue_.emplace_back(std::move(closure));
  changed_.notify_all();
}

void LoopClosureFeed::drain() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return queue_.empty() && !busy_; });
}

void LoopClosureFeed::stop() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;
    stopping_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

size_t LoopClosureFeed::queued() const {
  std::lock_guard lock(mutex_);
  return queued_frames_;
}

void LoopClosureFeed::run() {
  std::unique_lock lock(mutex_);
  for (;;) {
    changed_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
    if (queue_.empty()) break;  // stopping, and what was queued is done
    std::variant<Frame, LoopClosure> item = std::move(queue_.front());
    queue_.pop_front();
    if (std::holds_alternative<Frame>(item)) --queued_frames_;
    busy_ = true;
    changed_.notify_all();  // room in the queue
    lock.unlock();
    if (Frame* frame = std::get_if<Frame>(&item)) {
      process(*frame);
    } else {
      deliver(std::get<LoopClosure>(item));
    }
    lock.lock();
    busy_ = false;
    changed_.notify_all();
  }
}

void LoopClosureFeed::process(Frame& frame) {
  Recognizer& source = recognizers_.at(frame.kind);
  const auto start = std::chrono::steady_clock::now();
  std::optional<PlaceRecognizer::Match> match;
  try {
    match = source.recognizer->addFrame(frame.image(), frame.place.robot_id);
  } catch (const std::invalid_argument& e) {
    metrics_.loop_frames_refused.fetch_add(1, std::memory_order_relaxed);
    spdlog::warn("map {}: {} frame of {} at {} ns not used for place recognition: {}", map_,
                 toString(sourceOf(frame.kind)), frame.place.robot_id, frame.place.stamp_ns, e.what());
    return;
  }
  source.places.push_back(std::move(frame.place));
  metrics_.loop_frames.fetch_add(1, std::memory_order_relaxed);
  metrics_.loop_frame_latency.observe(
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (!match) return;
  const auto reference = static_cast<size_t>(match->reference_frame);
  if (match->reference_frame < 0 || reference + 1 >= source.places.size()) {
    spdlog::error("map {}: {} recognizer matched frame {} of {}; ignored", map_, toString(sourceOf(frame.kind)),
                  match->reference_frame, source.places.size());
    return;
  }
  const LoopPlace &query = source.places.back(), &older = source.places[reference];
  const std::optional<PoseTolerance> tolerance = source.recognizer->measuredPoseTolerance();
  if (tolerance && match->reference_from_query && query.pose && older.pose) {
    const Eigen::Isometry3d disagreement =
        (older.pose->inverse() * *query.pose).inverse() * *match->reference_from_query;
    const double off_m = disagreement.translation().norm();
    const double off_rad = Eigen::AngleAxisd(disagreement.linear()).angle();
    if (off_m > tolerance->translation_m || off_rad > tolerance->rotation_rad) {
      metrics_.loop_closures_refused.fetch_add(1, std::memory_order_relaxed);
      spdlog::info("map {}: {} closure of {} at {} ns with {} at {} ns refused: its measured relative pose lies "
                   "{:.2f} m and {:.1f}° from the places' poses",
                   map_, toString(sourceOf(frame.kind)), query.robot_id, query.stamp_ns, older.robot_id,
                   older.stamp_ns, off_m, off_rad * 180.0 / M_PI);
      return;
    }
  }
  deliver({map_, sourceOf(frame.kind), query, older, match->score, match->reference_from_query});
}

void LoopClosureFeed::deliver(const LoopClosure& closure) {
  if (!sink_) return;
  try {
    sink_(closure);
  } catch (const std::exception& e) {
    spdlog::error("map {}: loop closure not stored: {}", map_, e.what());
  }
}

}  // namespace rmap::app
