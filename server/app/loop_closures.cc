#include "app/loop_closures.h"

namespace rmap::app {

namespace {

/// {position [x,y,z], orientation [w,x,y,z]} of a pose, or nulls.
nlohmann::json poseJson(const std::optional<Eigen::Isometry3d>& pose) {
  if (!pose) return {{"position", nullptr}, {"orientation", nullptr}};
  const Eigen::Vector3d p = pose->translation();
  const Eigen::Quaterniond q(pose->linear());
  return {{"position", {p.x(), p.y(), p.z()}}, {"orientation", {q.w(), q.x(), q.y(), q.z()}}};
}

nlohmann::json placeJson(const LoopPlace& place) {
  nlohmann::json out{{"robot_id", place.robot_id}, {"stamp_ns", place.stamp_ns}};
  out.update(poseJson(place.pose));
  return out;
}

}  // namespace

const char* toString(LoopSource source) {
  switch (source) {
    case LoopSource::kCamera: return "camera";
    case LoopSource::kLaserIntensity: return "laser_intensity";
    case LoopSource::kGeometry: return "geometry";
  }
  return "camera";
}

std::optional<LoopSource> parseLoopSource(std::string_view name) {
  for (LoopSource s : {LoopSource::kCamera, LoopSource::kLaserIntensity, LoopSource::kGeometry}) {
    if (name == toString(s)) return s;
  }
  return std::nullopt;
}

store::LoopClosureRecord toRecord(const LoopClosure& c, int64_t detected_ns) {
  // The body keeps what the store does not index: the poses and the score.
  nlohmann::json body{{"score", c.score}, {"query", placeJson(c.query)}, {"match", placeJson(c.match)}};
  if (c.match_from_query) body["relative_pose"] = poseJson(c.match_from_query);
  if (c.ambiguous_direction) {
    const Eigen::Vector3d& d = *c.ambiguous_direction;
    body["ambiguous_direction"] = {d.x(), d.y(), d.z()};
  }
  return {0,
          c.map,
          toString(c.source),
          c.query.robot_id,
          c.query.stamp_ns,
          c.match.robot_id,
          c.match.stamp_ns,
          detected_ns,
          body.dump(),
          std::nullopt};
}

nlohmann::json loopClosureJson(const store::LoopClosureRecord& r) {
  const nlohmann::json body = nlohmann::json::parse(r.json);
  return {{"id", r.id},
          {"map", r.map},
          {"source", r.source},
          {"score", body.at("score")},
          {"detected_ns", r.detected_ns},
          {"query", body.at("query")},
          {"match", body.at("match")},
          // Closures stored before these were measured have neither.
          {"relative_pose", body.value("relative_pose", nlohmann::json(nullptr))},
          {"ambiguous_direction", body.value("ambiguous_direction", nlohmann::json(nullptr))},
          {"withdrawn_ns", r.withdrawn_ns ? nlohmann::json(*r.withdrawn_ns) : nlohmann::json(nullptr)}};
}

}  // namespace rmap::app
