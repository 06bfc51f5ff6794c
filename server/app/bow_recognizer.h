#pragma once
/// @file bow_recognizer.h
/// Place recognition of rmapd: server/loop's incremental bag-of-words loop
/// detector (ORB, its fixed defaults) behind the PlaceRecognizer seam.

#include "app/config.h"
#include "app/place_recognizer.h"
#include "loop/loop_detector.h"

namespace rmap::app {

class BowRecognizer : public PlaceRecognizer {
 public:
  explicit BowRecognizer(loop::LoopDetectorOptions options = {});
  /// The detector's accepted candidate (score: its acceptance score, the verified inliers).
  /// Each robot is a stream of the detector.
  std::optional<Match> addFrame(const PlaceImage& image, const std::string& robot_id) override;

 private:
  loop::LoopDetector detector_;
};

/// A BowRecognizer for each kind of frame the config turns on.
RecognizerFactory bowRecognizers(const LoopClosureConfig& config);

}  // namespace rmap::app
