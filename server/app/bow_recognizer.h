#pragma once
/// @file bow_recognizer.h
/// Place recognition of rmapd: server/loop's incremental bag-of-words loop
/// detector (ORB, its fixed defaults) behind the PlaceRecognizer seam.

#include <functional>

#include "app/config.h"
#include "app/place_recognizer.h"
#include "loop/loop_detector.h"

namespace rmap::app {

class BowRecognizer : public PlaceRecognizer {
 public:
  /// What the motion of a verified candidate's pixels (loop::LoopCandidate::reference_from_query_px)
  /// means in metres, for metric images: the older place's sensor frame from the new one's.
  using PixelMotionInMetres = std::function<Eigen::Isometry3d(const Eigen::Isometry2d& reference_from_query_px)>;

  /// @param pixel_motion  empty: the pixels' motion measures nothing (camera images)
  /// @param measured_pose_tolerance  PlaceRecognizer::measuredPoseTolerance
  explicit BowRecognizer(loop::LoopDetectorOptions options = {}, PixelMotionInMetres pixel_motion = {},
                         std::optional<PoseTolerance> measured_pose_tolerance = std::nullopt);
  /// The detector's accepted candidate (score: its acceptance score, the verified inliers), with
  /// the measured relative pose of a 3D fit, or of a 2D fit through pixel_motion.
  /// Each robot is a stream of the detector.
  std::optional<Match> addFrame(const PlaceImage& image, const std::string& robot_id) override;
  std::optional<PoseTolerance> measuredPoseTolerance() const override { return measured_pose_tolerance_; }

 private:
  loop::LoopDetector detector_;
  PixelMotionInMetres pixel_motion_;
  std::optional<PoseTolerance> measured_pose_tolerance_;
};

/// A BowRecognizer for each kind of frame the config turns on.
/// @param slam_loops  the 2D SLAM's loop closure: its widest search window bounds the motion a
///                    reflectivity-patch match may measure between the SLAM's poses
RecognizerFactory bowRecognizers(const LoopClosureConfig& config, const slam2d::LoopClosureOptions& slam_loops = {});

}  // namespace rmap::app
