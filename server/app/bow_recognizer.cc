#include "app/bow_recognizer.h"

#include "loop/reflectivity_patch.h"
#include "slam2d/loop_closure.h"

namespace rmap::app {

BowRecognizer::BowRecognizer(loop::LoopDetectorOptions options, PixelMotionInMetres pixel_motion,
                             std::optional<PoseTolerance> measured_pose_tolerance)
    : detector_(std::move(options)),
      pixel_motion_(std::move(pixel_motion)),
      measured_pose_tolerance_(measured_pose_tolerance) {}

std::optional<PlaceRecognizer::Match> BowRecognizer::addFrame(const PlaceImage& image, const std::string& robot_id) {
  const loop::FrameResult result = detector_.addFrame(image, robot_id);
  if (!result.accepted || !result.best) return std::nullopt;
  const loop::LoopCandidate& best = *result.best;
  Match match{best.reference_frame, best.score, best.reference_from_query};
  if (!match.reference_from_query && pixel_motion_ && best.reference_from_query_px) {
    match.reference_from_query = pixel_motion_(*best.reference_from_query_px);
  }
  return match;
}

RecognizerFactory bowRecognizers(const LoopClosureConfig& config, const slam2d::LoopClosureOptions& slam_loops) {
  const PoseTolerance patch_tolerance{slam_loops.max_window_m, slam_loops.max_window_rad};
  return [config, patch_tolerance](FrameKind kind) -> std::unique_ptr<PlaceRecognizer> {
    const bool on = kind == FrameKind::kCamera              ? config.camera
                    : kind == FrameKind::kIntensityPanorama ? config.cloud_intensity
                                                            : config.reflectivity_patches;
    if (!on) return nullptr;
    loop::LoopDetectorOptions options =
        kind == FrameKind::kIntensityPanorama ? loop::panoramaDetectorOptions() : loop::LoopDetectorOptions{};
    BowRecognizer::PixelMotionInMetres pixel_motion;
    std::optional<PoseTolerance> tolerance;
    if (kind == FrameKind::kReflectivityPatch) {
      // A reflectivity patch is a metric top-down picture: a revisit is the same picture turned and
      // shifted, by the robot's motion between the two patches' centres.
      options.verification.model = loop::GeometricModel::kRigid2d;
      pixel_motion = [](const Eigen::Isometry2d& reference_from_query_px) {
        // The patches MapWorker cuts: default options.
        return slam2d::planarIsometry(loop::patchMotion(reference_from_query_px, loop::PatchOptions{}));
      };
      // Patches are cut from the map all robots draw: another robot's recent patch shows what this one drew.
      options.exclusion_window_all_streams = true;
      // ...around the poses its 2D SLAM gave them, in one frame: two patches of one place lie where
      // those poses say, but for the drift the SLAM's own loop search still corrects (its widest
      // window). A look-alike elsewhere fits a motion the poses deny (seen: turned 180°).
      tolerance = patch_tolerance;
    }
    return std::make_unique<BowRecognizer>(std::move(options), std::move(pixel_motion), tolerance);
  };
}

}  // namespace rmap::app
