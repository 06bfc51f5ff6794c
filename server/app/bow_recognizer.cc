#include "app/bow_recognizer.h"

namespace rmap::app {

BowRecognizer::BowRecognizer(loop::LoopDetectorOptions options) : detector_(std::move(options)) {}

std::optional<PlaceRecognizer::Match> BowRecognizer::addFrame(const PlaceImage& image) {
  const loop::FrameResult result = detector_.addFrame(image);
  if (!result.accepted || !result.best) return std::nullopt;
  return Match{result.best->reference_frame, result.best->score};
}

RecognizerFactory bowRecognizers(const LoopClosureConfig& config) {
  return [config](FrameKind kind) -> std::unique_ptr<PlaceRecognizer> {
    const bool on = kind == FrameKind::kCamera              ? config.camera
                    : kind == FrameKind::kIntensityPanorama ? config.cloud_intensity
                                                            : config.reflectivity_patches;
    if (!on) return nullptr;
    loop::LoopDetectorOptions options;
    // A reflectivity patch is a metric top-down picture: a revisit is the same picture turned and shifted.
    if (kind == FrameKind::kReflectivityPatch) options.verification.model = loop::GeometricModel::kRigid2d;
    // A panorama's pixels carry their points: a revisit is the same points moved rigidly in metres.
    if (kind == FrameKind::kIntensityPanorama) options.verification.model = loop::GeometricModel::kRigid3d;
    return std::make_unique<BowRecognizer>(std::move(options));
  };
}

}  // namespace rmap::app
