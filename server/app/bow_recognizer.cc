#include "app/bow_recognizer.h"

namespace rmap::app {

BowRecognizer::BowRecognizer(loop::LoopDetectorOptions options) : detector_(std::move(options)) {}

std::optional<PlaceRecognizer::Match> BowRecognizer::addFrame(const PlaceImage& image, const std::string& robot_id) {
  const loop::FrameResult result = detector_.addFrame(image, robot_id);
  if (!result.accepted || !result.best) return std::nullopt;
  return Match{result.best->reference_frame, result.best->score, result.best->reference_from_query};
}

RecognizerFactory bowRecognizers(const LoopClosureConfig& config) {
  return [config](FrameKind kind) -> std::unique_ptr<PlaceRecognizer> {
    const bool on = kind == FrameKind::kCamera              ? config.camera
                    : kind == FrameKind::kIntensityPanorama ? config.cloud_intensity
                                                            : config.reflectivity_patches;
    if (!on) return nullptr;
    loop::LoopDetectorOptions options =
        kind == FrameKind::kIntensityPanorama ? loop::panoramaDetectorOptions() : loop::LoopDetectorOptions{};
    if (kind == FrameKind::kReflectivityPatch) {
      // A reflectivity patch is a metric top-down picture: a revisit is the same picture turned and shifted.
      options.verification.model = loop::GeometricModel::kRigid2d;
      // Patches are cut from the map all robots draw: another robot's recent patch shows what this one drew.
      options.exclusion_window_all_streams = true;
    }
    return std::make_unique<BowRecognizer>(std::move(options));
  };
}

}  // namespace rmap::app
