#include "app/loop_closure_feed.h"

#include <gtest/gtest.h>

#include <atomic>
#include <future>
#include <mutex>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <thread>

#include "same_grey_recognizer.h"

namespace rmap::app {
namespace {

using testing::SameGreyRecognizer;

LoopClosureFeed::Frame frame(FrameKind kind, const std::string& robot, int64_t stamp_ns, uint8_t grey) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation().x() = static_cast<double>(stamp_ns);
  return {kind, {robot, stamp_ns, pose}, [grey] { return cv::Mat(32, 32, CV_8UC1, cv::Scalar(grey)); }};
}

struct Collected {
  std::mutex mutex;
  std::vector<LoopClosure> closures;
  LoopClosureSink sink() {
    return [this](const LoopClosure& c) {
      std::lock_guard lock(mutex);
      closures.push_back(c);
    };
  }
};

TEST(LoopClosureFeed, AcceptedMatchesBecomeClosuresBetweenTheFramesPlaces) {
  Metrics metrics;
  Collected out;
  LoopClosureFeed feed(
      "lab", [](FrameKind kind) -> std::unique_ptr<PlaceRecognizer> {
        if (kind == FrameKind::kIntensityPanorama) return nullptr;  // that kind is off
        return std::make_unique<SameGreyRecognizer>();
      },
      out.sink(), metrics, 4);
  EXPECT_TRUE(feed.accepts(FrameKind::kCamera));
  EXPECT_TRUE(feed.accepts(FrameKind::kReflectivityPatch));
  EXPECT_FALSE(feed.accepts(FrameKind::kIntensityPanorama));
  EXPECT_THROW(feed.push(frame(FrameKind::kIntensityPanorama, "r1", 1, 10), true), std::invalid_argument);

  feed.push(frame(FrameKind::kCamera, "r1", 1, 100), true);
  feed.push(frame(FrameKind::kReflectivityPatch, "r2", 2, 100), true);  // another recognizer: no match across kinds
  feed.push(frame(FrameKind::kCamera, "r1", 3, 50), true);
  // A frame that does not decode is skipped and takes no frame index.
  feed.push({FrameKind::kCamera, {"r1", 4, std::nullopt}, []() -> cv::Mat { throw std::invalid_argument("bad"); }},
            true);
  feed.push(frame(FrameKind::kCamera, "r2", 5, 100), true);  // camera frame 2 matches frame 0
  feed.drain();

  ASSERT_EQ(out.closures.size(), 1u);
  const LoopClosure& c = out.closures[0];
  EXPECT_EQ(c.map, "lab");
  EXPECT_EQ(c.source, LoopSource::kCamera);
  EXPECT_EQ(c.query.robot_id, "r2");
  EXPECT_EQ(c.query.stamp_ns, 5);
  ASSERT_TRUE(c.query.pose);
  EXPECT_EQ(c.query.pose->translation().x(), 5.0);
  EXPECT_EQ(c.match.robot_id, "r1");
  EXPECT_EQ(c.match.stamp_ns, 1);
  EXPECT_NEAR(c.score, 100.0 / 255.0, 1e-12);
  EXPECT_EQ(metrics.loop_frames.load(), 4u);
  EXPECT_EQ(metrics.loop_frames_refused.load(), 1u);
}

/// SameGreyRecognizer measuring every match's query 2 m ahead (x) of the older frame, and
/// refusing what lies more than 0.5 m or 0.1 rad from the places' poses.
class MeasuringRecognizer : public SameGreyRecognizer {
 public:
  std::optional<Match> addFrame(const PlaceImage& image, const std::string& robot_id) override {
    std::optional<Match> match = SameGreyRecognizer::addFrame(image, robot_id);
    if (match) match->reference_from_query = Eigen::Isometry3d(Eigen::Translation3d(2.0, 0.0, 0.0));
    return match;
  }
  std::optional<PoseTolerance> measuredPoseTolerance() const override { return PoseTolerance{0.5, 0.1}; }
};

TEST(LoopClosureFeed, AMatchWhoseMeasuredPoseContradictsThePlacesPosesIsRefused) {
  Metrics metrics;
  Collected out;
  LoopClosureFeed feed(
      "lab", [](FrameKind) { return std::make_unique<MeasuringRecognizer>(); }, out.sink(), metrics, 4);
  // frame() puts the place at x = stamp (m): stamp 3 lies 2 m ahead of stamp 1, as measured;
  // stamp 7, 6 m ahead, does not.
  for (const auto& [stamp, grey] : {std::pair{1, 100}, {2, 50}, {3, 100}, {4, 60}, {7, 100}}) {
    feed.push(frame(FrameKind::kReflectivityPatch, "r1", stamp, static_cast<uint8_t>(grey)), true);
  }
  feed.drain();
  ASSERT_EQ(out.closures.size(), 1u);
  EXPECT_EQ(out.closures[0].query.stamp_ns, 3);
  EXPECT_EQ(out.closures[0].match.stamp_ns, 1);
  ASSERT_TRUE(out.closures[0].match_from_query);
  EXPECT_EQ(out.closures[0].match_from_query->translation().x(), 2.0);
  EXPECT_EQ(metrics.loop_closures_refused.load(), 1u);
}

TEST(LoopClosureFeed, PostedClosuresReachTheSinkInOrderWithTheFrames) {
  Metrics metrics;
  Collected out;
  LoopClosureFeed feed(
      "lab", [](FrameKind) { return std::make_unique<SameGreyRecognizer>(); }, out.sink(), metrics, 1);
  for (int64_t i = 0; i < 3; ++i) feed.push(frame(FrameKind::kCamera, "r1", i, i == 2 ? 40 : 40 + i), true);
  // Posted after the frames (the queue bound is for frames only): delivered after their closure.
  for (int64_t i = 0; i < 3; ++i) {
    feed.post({"lab", LoopSource::kGeometry, {"r2", 100 + i, std::nullopt}, {"r1", i, std::nullopt}, 0.5, std::nullopt});
  }
  feed.drain();
  ASSERT_EQ(out.closures.size(), 4u);
  EXPECT_EQ(out.closures[0].source, LoopSource::kCamera);
  for (int i = 1; i < 4; ++i) {
    EXPECT_EQ(out.closures[i].source, LoopSource::kGeometry);
    EXPECT_EQ(out.closures[i].query.stamp_ns, 100 + i - 1);
  }
}

TEST(LoopClosureFeed, PatchClosuresReportLaserIntensity) {
  Metrics metrics;
  Collected out;
  LoopClosureFeed feed(
      "lab", [](FrameKind) { return std::make_unique<SameGreyRecognizer>(); }, out.sink(), metrics, 4);
  for (int64_t i = 0; i < 3; ++i) feed.push(frame(FrameKind::kReflectivityPatch, "r1", i, i == 2 ? 7 : 7 + i), true);
  feed.drain();
  ASSERT_EQ(out.closures.size(), 1u);
  EXPECT_EQ(out.closures[0].source, LoopSource::kLaserIntensity);
}

TEST(LoopClosureFeed, ALiveFrameFindingTheQueueFullIsDroppedAtOnce) {
  Metrics metrics;
  Collected out;
  std::promise<void> open;
  std::shared_future<void> gate = open.get_future().share();
  LoopClosureFeed feed(
      "lab", [&](FrameKind) { return std::make_unique<SameGreyRecognizer>(gate); }, out.sink(), metrics, 1);
  EXPECT_TRUE(feed.push(frame(FrameKind::kCamera, "r1", 0, 10), false));  // taken by the blocked recognizer
  ASSERT_TRUE([&] {
    for (int i = 0; i < 200 && feed.queued() > 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    return feed.queued() == 0;
  }());
  EXPECT_TRUE(feed.push(frame(FrameKind::kCamera, "r1", 1, 20), false));  // queued
  EXPECT_FALSE(feed.push(frame(FrameKind::kCamera, "r1", 2, 30), false));  // full: dropped, no wait
  EXPECT_EQ(metrics.loop_frames_dropped.load(), 1u);
  open.set_value();
  feed.drain();
  EXPECT_EQ(metrics.loop_frames.load(), 2u);
}

TEST(LoopClosureFeed, AFullQueueHoldsAWaitingPusherBackAndDropsNothing) {
  Metrics metrics;
  Collected out;
  std::promise<void> open;
  std::shared_future<void> gate = open.get_future().share();
  LoopClosureFeed feed(
      "lab", [&](FrameKind) { return std::make_unique<SameGreyRecognizer>(gate); }, out.sink(), metrics, 2);
  // One frame in the (blocked) recognizer, two queued: the fourth push waits.
  std::atomic<int> pushed{0};
  std::thread pusher([&] {
    for (int64_t i = 0; i < 4; ++i) {
      EXPECT_TRUE(feed.push(frame(FrameKind::kCamera, "r1", i, i == 3 ? 0 : static_cast<uint8_t>(10 + i)), true));
      ++pushed;
    }
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_EQ(pushed.load(), 3);
  EXPECT_EQ(feed.queued(), 2u);
  open.set_value();
  pusher.join();
  feed.drain();
  EXPECT_EQ(pushed.load(), 4);
  EXPECT_EQ(metrics.loop_frames.load(), 4u);
}

TEST(LoopClosureFeed, StopProcessesWhatIsQueued) {
  Metrics metrics;
  Collected out;
  {
    LoopClosureFeed feed(
        "lab", [](FrameKind) { return std::make_unique<SameGreyRecognizer>(); }, out.sink(), metrics, 8);
    for (int64_t i = 0; i < 4; ++i) feed.push(frame(FrameKind::kCamera, "r1", i, i == 3 ? 20 : 20 + i), true);
  }
  EXPECT_EQ(metrics.loop_frames.load(), 4u);
  EXPECT_EQ(out.closures.size(), 1u);
}

TEST(LoopClosureFeed, QueueBoundMustBePositive) {
  Metrics metrics;
  EXPECT_THROW(LoopClosureFeed("lab", nullptr, nullptr, metrics, 0), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::app
