#include "app/http_api.h"

#include <spdlog/spdlog.h>

#include <chrono>

#include "app/ingest.h"
#include "app/loop_closures.h"
#include "net/json_error.h"

namespace rmap::app {

namespace http = boost::beast::http;

namespace {

void requireMethod(const net::Request& request, http::verb verb) {
  if (request.method() != verb) {
    const std::string_view method(request.method_string().data(), request.method_string().size());
    throw ApiError::methodNotAllowed(method, std::string(http::to_string(verb)));
  }
}

nlohmann::json boxJson(const map3d::Grid& grid, const map3d::CellKey& min, const map3d::CellKey& max) {
  const double r = grid.resolution();
  return {{"min", {min.x * r, min.y * r, min.z * r}}, {"max", {(max.x + 1) * r, (max.y + 1) * r, (max.z + 1) * r}}};
}

}  // namespace

nlohmann::json mapJson(const MapWorker& worker) {
  const map3d::CuboidMap& map = worker.map();
  const map3d::MapStats stats = map.stats();
  nlohmann::json out{{"name", worker.name()},
                     {"resolution_m", map.resolution()},
                     {"version", stats.version},
                     {"cuboids", stats.cuboids},
                     {"blocks", stats.blocks},
                     {"known_cells", stats.known_cells},
                     {"occupied_cells", stats.occupied_cells},
                     {"memory_bytes", stats.memory_bytes},
                     {"scans", stats.scans},
                     {"applied_message_id", worker.appliedId()},
                     {"bounds", nullptr}};
  map3d::CellKey min, max;
  if (map.bounds(min, max)) out["bounds"] = boxJson(map.grid(), min, max);
  return out;
}

HttpApi::HttpApi(MappingService& service, const Authenticator& auth)
    : service_(service), auth_(auth), static_files_(service.config().web_root) {}

net::Response HttpApi::handle(net::Request& request, const net::Peer& peer) {
  const auto start = std::chrono::steady_clock::now();
  Metrics& metrics = service_.metrics();
  net::Response response;
  try {
    const std::string_view raw(request.target().data(), request.target().size());
    response = route(request, peer, Target::parse(raw));
  } catch (const ApiError& e) {
    response = net::jsonError(static_cast<http::status>(e.status()), e.code(), e.what(), request.version(),
                              request.keep_alive());
    if (!e.allow().empty()) response.set(http::field::allow, e.allow());
  } catch (const std::invalid_argument& e) {
    response = net::jsonError(http::status::bad_request, "invalid_argument", e.what(), request.version(),
                              request.keep_alive());
  } catch (const std::exception& e) {
    spdlog::error("{} {}: {}", std::string(request.method_string()), std::string(request.target()), e.what());
    response = net::internalError(request.version(), request.keep_alive());
  }
  // A HEAD answer carries the length of the body it omits, whatever the route; a body would be
  // read as the start of the next response on a kept-alive connection.
  if (request.method() == http::verb::head && !response.body().empty()) {
    const size_t length = response.body().size();
    response.body().clear();
    response.content_length(length);
  }
  metrics.http_requests.fetch_add(1, std::memory_order_relaxed);
  if (response.result_int() >= 400) metrics.http_errors.fetch_add(1, std::memory_order_relaxed);
  metrics.http_latency.observe(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return response;
}

net::Response HttpApi::route(net::Request& request, const net::Peer& peer, const Target& target) {
  const std::vector<std::string>& s = target.segments;
  if (s.size() == 1 && s[0] == "healthz") {
    requireMethod(request, http::verb::get);
    return health(request);
  }
  if (std::optional<net::Response> file = static_files_.serve(request, s)) return std::move(*file);
  const AuthResult auth = auth_.authenticate(request, peer);
  if (!auth.principal) throw ApiError(auth.status, auth.code, auth.message);
  if (s.size() == 1 && s[0] == "metrics") {
    if (auth.principal->role != Role::kAdmin) throw ApiError(403, "permission_denied", "metrics need an admin token");
    requireMethod(request, http::verb::get);
    return metrics(request);
  }
  if (s.size() < 2 || s[0] != "v1") throw ApiError(404, "not_found", "no such endpoint");
  if (s[1] == "maps") {
    if (s.size() == 2) {
      requireMethod(request, http::verb::get);
      return listMaps(request);
    }
    if (constexpr std::string_view kImport = ":import"; s.size() == 3 && s[2].ends_with(kImport)) {
      // Before the map lookup: an import creates its map when missing.
      if (auth.principal->role != Role::kAdmin) {
        throw ApiError(403, "permission_denied", "importing a map needs an admin token");
      }
      requireMethod(request, http::verb::post);
      return importMap(request, target, s[2].substr(0, s[2].size() - kImport.size()));
    }
    const std::shared_ptr<MapWorker> map = service_.findMap(s[2]);
    if (!map) throw ApiError(404, "map_not_found", "no map named '" + s[2] + "'");
    if (s.size() == 3) {
      requireMethod(request, http::verb::get);
      return describeMap(request, *map);
    }
    if (s.size() == 4 && s[3] == "occupancy:batch") {
      requireMethod(request, http::verb::post);
      return occupancyBatch(request, *map);
    }
    requireMethod(request, http::verb::get);
    if (s.size() == 4 && s[3] == "occupancy") return occupancy(request, target, *map);
    if (s.size() == 5 && s[3] == "occupancy" && s[4] == "box") return occupancyBox(request, target, *map);
    if (s.size() == 4 && s[3] == "tileset.json") return tileset(request, *map);
    if (s.size() == 8 && s[3] == "tiles") return tile(request, target, *map);
    if (s.size() == 4 && s[3] == "layers") return layers(request, *map);
    if (s.size() == 8 && s[3] == "layers") return layerTile(request, target, *map);
    if (s.size() == 4 && s[3] == "grid2d.pgm") return gridPgm(request, *map);
    if (s.size() == 4 && s[3] == "grid2d.yaml") return gridYaml(request, *map);
    if (s.size() == 5 && s[3] == "layers") return layerImage(request, s[4], *map);
    if (s.size() == 4 && s[3] == "export.bt") return exportBt(request, *map);
  } else if (s[1] == "robots") {
    requireMethod(request, http::verb::get);
    if (s.size() == 2) return listRobots(request);
    if (s.size() == 3) return describeRobot(request, s[2]);
    if (s.size() == 4 && s[3] == "trajectory") return trajectory(request, target, s[2]);
  } else if (s[1] == "loop-closures" && s.size() == 2) {
    requireMethod(request, http::verb::get);
    return loopClosures(request, target);
  }
  throw ApiError(404, "not_found", "no such endpoint");
}

net::Response HttpApi::health(const net::Request& request) {
  return jsonResponse(request, {{"status", "ok"}, {"version", MappingService::version()},
                                {"maps", service_.maps().size()}});
}

net::Response HttpApi::metrics(const net::Request& request) {
  return bodyResponse(request, renderPrometheus(service_.metrics(), service_.gauges()),
                      "text/plain; version=0.0.4; charset=utf-8");
}

net::Response HttpApi::listMaps(const net::Request& request) {
  nlohmann::json maps = nlohmann::json::array();
  for (const auto& worker : service_.maps()) maps.push_back(mapJson(*worker));
  return jsonResponse(request, {{"maps", std::move(maps)}});
}

net::Response HttpApi::describeMap(const net::Request& request, const MapWorker& map) {
  return jsonResponse(request, mapJson(map));
}

namespace {

nlohmann::json robotJson(const RobotStatus& robot) {
  nlohmann::json out{{"robot_id", robot.record.robot_id},
                     {"map", robot.record.map},
                     {"connected", robot.connected},
                     {"first_seen_ns", robot.record.first_seen_ns},
                     {"last_seen_ns", robot.record.last_seen_ns},
                     {"last_seq", robot.record.last_seq},
                     {"sensors", nlohmann::json::parse(robot.record.sensors_json.empty() ? "[]"
                                                                                         : robot.record.sensors_json)},
                     {"pose", nullptr}};
  if (robot.last_pose) out["pose"] = poseJson(*robot.last_pose);
  return out;
}

}  // namespace

net::Response HttpApi::listRobots(const net::Request& request) {
  nlohmann::json robots = nlohmann::json::array();
  for (const RobotStatus& robot : service_.robots()) robots.push_back(robotJson(robot));
  return jsonResponse(request, {{"robots", std::move(robots)}});
}

net::Response HttpApi::describeRobot(const net::Request& request, const std::string& robot_id) {
  const std::optional<RobotStatus> robot = service_.robot(robot_id);
  if (!robot) throw ApiError(404, "robot_not_found", "no robot with id '" + robot_id + "'");
  return jsonResponse(request, robotJson(*robot));
}

net::Response HttpApi::trajectory(const net::Request& request, const Target& target, const std::string& robot_id) {
  if (!service_.robot(robot_id)) throw ApiError(404, "robot_not_found", "no robot with id '" + robot_id + "'");
  const int64_t since_ns = target.integer("since_ns", INT64_MIN, INT64_MIN, INT64_MAX);
  const int64_t limit = target.integer("limit", 10000, 1, 1'000'000);
  nlohmann::json poses = nlohmann::json::array();
  for (const store::TrajectoryPose& p :
       service_.store().trajectory(robot_id, since_ns, static_cast<size_t>(limit))) {
    poses.push_back({{"stamp_ns", p.stamp_ns},
                     {"seq", p.seq},
                     {"position", {p.position_m[0], p.position_m[1], p.position_m[2]}},
                     {"orientation", {p.orientation_wxyz[0], p.orientation_wxyz[1], p.orientation_wxyz[2],
                                      p.orientation_wxyz[3]}}});
  }
  return jsonResponse(request, {{"robot_id", robot_id}, {"poses", std::move(poses)}});
}

net::Response HttpApi::loopClosures(const net::Request& request, const Target& target) {
  for (const auto& [key, value] : target.query) {
    if (key != "map" && key != "robot" && key != "source" && key != "since" && key != "limit") {
      throw ApiError(400, "invalid_argument",
                     "unknown query parameter '" + key + "'; use map, robot, source, since, limit");
    }
  }
  store::LoopClosureFilter filter;
  filter.map = target.text("map");
  if (!filter.map.empty() && !service_.findMap(filter.map)) {
    throw ApiError(404, "map_not_found", "no map named '" + filter.map + "'");
  }
  filter.robot = target.text("robot");
  if (!filter.robot.empty() && !validName(filter.robot)) {
    throw ApiError(400, "invalid_argument", "robot must be 1..64 characters of [A-Za-z0-9._-]");
  }
  if (!filter.robot.empty() && !service_.robot(filter.robot)) {
    throw ApiError(404, "robot_not_found", "no robot with id '" + filter.robot + "'");
  }
  filter.source = target.text("source");
  if (!filter.source.empty() && !parseLoopSource(filter.source)) {
    throw ApiError(400, "invalid_argument",
                   "source must be camera, laser_intensity or geometry, not '" + filter.source + "'");
  }
  filter.after_id = target.integer("since", 0, 0, INT64_MAX);
  filter.limit = static_cast<size_t>(target.integer("limit", 1000, 1, 100'000));
  nlohmann::json closures = nlohmann::json::array();
  for (const store::LoopClosureRecord& r : service_.store().loopClosures(filter)) {
    closures.push_back(loopClosureJson(r));
  }
  return jsonResponse(request, {{"loop_closures", std::move(closures)}});
}

}  // namespace rmap::app
