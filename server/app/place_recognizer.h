#pragma once
/// @file place_recognizer.h
/// The seam between rmapd and a place recognition engine: a stream of 8-bit
/// grey frames in, accepted matches with older frames out. One instance per
/// map and kind of frame, fed in log order.

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include <opencv2/core/mat.hpp>

#include "app/loop_closures.h"
#include "loop/point_image.h"

namespace rmap::app {

/// The images place recognition runs on; each kind has its own recognizer
/// (their images do not look alike, so they are never compared).
enum class FrameKind {
  kCamera,              ///< camera images
  kIntensityPanorama,   ///< panoramas of the intensities of 3D clouds
  kReflectivityPatch,   ///< patches of the 2D map's reflectivity layer around 2D-laser robots
};
inline constexpr FrameKind kFrameKinds[] = {FrameKind::kCamera, FrameKind::kIntensityPanorama,
                                            FrameKind::kReflectivityPatch};
/// The source a loop closure found on frames of `kind` reports.
inline LoopSource sourceOf(FrameKind kind) {
  return kind == FrameKind::kCamera ? LoopSource::kCamera : LoopSource::kLaserIntensity;
}

using loop::PlaceImage;

/// How far a measured relative pose may lie from the one between two places' poses.
struct PoseTolerance {
  double translation_m = 0.0;
  double rotation_rad = 0.0;
};

class PlaceRecognizer {
 public:
  struct Match {
    int64_t reference_frame = -1;  ///< 0-based index of the older frame
    double score = 0.0;            ///< acceptance score, higher = surer
    /// The new frame's sensor pose in the older frame's sensor frame (metres), when measured.
    std::optional<Eigen::Isometry3d> reference_from_query;
  };
  virtual ~PlaceRecognizer() = default;
  /// Adds the next frame (its index is the number of frames added before) of `robot_id`:
  /// frames of several robots interleave, and an engine keeps each robot's sequence apart.
  /// @return the older frame it closes a loop with, when the engine accepts one
  /// @throws std::invalid_argument for an image the engine cannot use (state unchanged)
  virtual std::optional<Match> addFrame(const PlaceImage& image, const std::string& robot_id) = 0;
  /// For frames whose places' poses all come from one consistent estimate (the map's own 2D
  /// SLAM): how far a true match's measured relative pose can lie from the one between the two
  /// places' poses (the drift that estimate can hold). A match beyond it is refused. None: not checked.
  virtual std::optional<PoseTolerance> measuredPoseTolerance() const { return std::nullopt; }
};

/// Makes the recognizer of a kind of frame, or nullptr when that kind is off.
using RecognizerFactory = std::function<std::unique_ptr<PlaceRecognizer>(FrameKind)>;

}  // namespace rmap::app
