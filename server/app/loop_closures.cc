#include "app/loop_closures.h"

namespace rmap::app {

namespace {

nlohmann::json placeJson(const LoopPlace& place) {
  nlohmann::json out{{"robot_id", place.robot_id}, {"stamp_ns", place.stamp_ns}, {"position", nullptr},
                     {"orientation", nullptr}};
  if (place.pose) {
    const Eigen::Vector3d p = place.pose->translation();
    const Eigen::Quaterniond q(place.pose->linear());
    out["position"] = {p.x(), p.y(), p.z()};
    out["orientation"] = {q.w(), q.x(), q.y(), q.z()};
  }
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
  const nlohmann::json body{{"score", c.score}, {"query", placeJson(c.query)}, {"match", placeJson(c.match)}};
  return {0,
          c.map,
          toString(c.source),
          c.query.robot_id,
          c.query.stamp_ns,
          c.match.robot_id,
          c.match.stamp_ns,
          detected_ns,
          body.dump()};
}

nlohmann::json loopClosureJson(const store::LoopClosureRecord& r) {
  const nlohmann::json body = nlohmann::json::parse(r.json);
  return {{"id", r.id},
          {"map", r.map},
          {"source", r.source},
          {"score", body.at("score")},
          {"detected_ns", r.detected_ns},
          {"query", body.at("query")},
          {"match", body.at("match")}};
}

}  // namespace rmap::app
