#include "app/bow_recognizer.h"

namespace rmap::app {

BowRecognizer::BowRecognizer(loop::LoopDetectorOptions options) : detector_(std::move(options)) {}

std::optional<PlaceRecognizer::Match> BowRecognizer::addFrame(const cv::Mat& gray) {
  const loop::FrameResult result = detector_.addFrame(gray);
  if (!result.accepted || !result.best) return std::nullopt;
  return Match{result.best->reference_frame, result.best->score};
}

RecognizerFactory bowRecognizers(const LoopClosureConfig& config) {
  return [config](FrameKind kind) -> std::unique_ptr<PlaceRecognizer> {
    const bool on = kind == FrameKind::kCamera              ? config.camera
                    : kind == FrameKind::kIntensityPanorama ? config.cloud_intensity
                                                            : config.reflectivity_patches;
    return on ? std::make_unique<BowRecognizer>() : nullptr;
  };
}

}  // namespace rmap::app
