#pragma once
/// @file loop_closures.h
/// A loop closure as rmapd reports it: two places of robots on one map that
/// are the same place, found by a camera, by laser intensities or by the 2D
/// SLAM's geometry; its stored form and its JSON for the API and the viewers.

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "store/store.h"

namespace rmap::app {

/// What found a loop closure (the API's `source`).
enum class LoopSource { kCamera, kLaserIntensity, kGeometry };
/// "camera", "laser_intensity", "geometry".
const char* toString(LoopSource source);
/// The source named `name`; nullopt for any other text.
std::optional<LoopSource> parseLoopSource(std::string_view name);

/// One end of a loop closure: where a robot was at a time.
struct LoopPlace {
  std::string robot_id;
  int64_t stamp_ns = 0;
  /// Map frame pose of the sensor (camera, lidar) or robot base (2D), when known.
  std::optional<Eigen::Isometry3d> pose;
};

struct LoopClosure {
  std::string map;
  LoopSource source = LoopSource::kCamera;
  LoopPlace query;   ///< the newer place, whose frame found the loop
  LoopPlace match;   ///< the older place it matched
  double score = 0;  ///< the detector's acceptance score (higher = surer; geometry: match score 0..1)
  /// The query place's sensor pose in the match place's sensor frame (metres), as the loop
  /// closure measured it (geometry: the scan-to-submap match; laser-intensity panoramas: the
  /// 3D rigid fit; reflectivity patches: the 2D rigid fit of their pixels); unknown otherwise.
  std::optional<Eigen::Isometry3d> match_from_query;
  /// The 2D pose graph dropped this closure, reported before, after later
  /// closures showed it wrong: the sink withdraws the stored one.
  bool withdrawn = false;
  /// A geometry closure from an ambiguous scan-to-submap match (a corridor,
  /// repeated structure): the unit direction, in the match place's frame,
  /// along which match_from_query is known only to about a metre (the pose
  /// graph holds it weakly that way); none for any other closure.
  std::optional<Eigen::Vector3d> ambiguous_direction{};
};

/// Takes accepted loop closures and withdrawals (store, viewers, metrics).
using LoopClosureSink = std::function<void(const LoopClosure&)>;

/// The stored form; `detected_ns` is the wall clock of the detection.
store::LoopClosureRecord toRecord(const LoopClosure& closure, int64_t detected_ns);
/// JSON of a stored loop closure: id, map, source, score, detected_ns,
/// query and match as {robot_id, stamp_ns, position [x,y,z] m, orientation [w,x,y,z]}
/// (position and orientation null when the pose is unknown), relative_pose
/// {position, orientation} (match_from_query; null when not measured), and
/// withdrawn_ns (null while the closure holds) and ambiguous_direction
/// ([x,y,z], unit, in the match place's frame; null for a closure that is
/// not ambiguous).
/// @throws nlohmann::json::exception when the stored body is not JSON
nlohmann::json loopClosureJson(const store::LoopClosureRecord& record);

}  // namespace rmap::app
