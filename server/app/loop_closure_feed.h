#pragma once
/// @file loop_closure_feed.h
/// Place recognition of one map on its own thread: frames (camera images,
/// laser-intensity images) queued by the map worker in log order go through
/// the recognizer of their source; each accepted match becomes a LoopClosure
/// between the two frames' places.
///
/// The queue is bounded. Live, a frame that finds it full is dropped (and
/// counted) rather than holding the worker, and with it the acks of later
/// messages, back; recovery waits instead, so a replay feeds every frame and
/// may find closures the live run skipped (never one twice: the store keeps
/// each closure once).

#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "app/loop_closures.h"
#include "app/metrics.h"
#include "app/place_recognizer.h"

namespace rmap::app {

class LoopClosureFeed {
 public:
  struct Frame {
    FrameKind kind = FrameKind::kCamera;
    LoopPlace place;
    /// Makes the image on the feed's thread (e.g. decodes a JPEG, projects a cloud).
    /// @throws std::invalid_argument when it cannot (the frame is skipped and counted)
    std::function<PlaceImage()> image;
  };

  /// @param factory     called once per kind of frame at construction
  /// @param max_queued  frames waiting at most, >= 1
  LoopClosureFeed(std::string map, const RecognizerFactory& factory, LoopClosureSink sink, Metrics& metrics,
                  size_t max_queued);
  /// stop().
  ~LoopClosureFeed();
  LoopClosureFeed(const LoopClosureFeed&) = delete;
  LoopClosureFeed& operator=(const LoopClosureFeed&) = delete;

  /// Whether frames of `kind` are recognised (its recognizer exists).
  bool accepts(FrameKind kind) const { return recognizers_.count(kind) > 0; }
  /// Queues a frame of an accepted kind. A full queue: waits when `wait`, else drops the frame.
  /// @return whether the frame was queued
  bool push(Frame frame, bool wait);
  /// Queues a closure found elsewhere (the 2D SLAM's) for the sink, after the frames queued
  /// before it: storing it (a durable write) then costs the map's worker nothing. Never drops
  /// nor waits.
  void post(LoopClosure closure);
  /// Waits until every queued frame went through its recognizer and every posted closure to the sink.
  void drain();
  /// Processes what is queued and joins the thread; later calls do nothing.
  void stop();
  /// Frames waiting (posted closures not included).
  size_t queued() const;

 private:
  struct Recognizer {
    std::unique_ptr<PlaceRecognizer> recognizer;
    std::vector<LoopPlace> places;  ///< one per frame the recognizer took, in its frame order
  };
  void run();
  void process(Frame& frame);
  void deliver(const LoopClosure& closure);

  std::string map_;
  std::map<FrameKind, Recognizer> recognizers_;
  LoopClosureSink sink_;
  Metrics& metrics_;
  size_t max_queued_;

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::variant<Frame, LoopClosure>> queue_;
  size_t queued_frames_ = 0;
  bool busy_ = false;  ///< a frame taken off the queue is being processed
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace rmap::app
