// Map queries of the HTTP API: point, batch, box, tileset and tiles.
#include <algorithm>
#include <queue>
#include <tuple>

#include "app/http_api.h"
#include "rmap/v1/map_api.pb.h"

namespace rmap::app {

namespace http = boost::beast::http;

namespace {

constexpr const char* kProtobuf = "application/x-protobuf";

nlohmann::json cuboidJson(const map3d::Grid& grid, const map3d::CuboidBox& c, const map3d::OccupancyParams& params) {
  const double r = grid.resolution();
  const double p = map3d::probability(c.log_odds);
  return {{"min", {c.min.x * r, c.min.y * r, c.min.z * r}},
          {"max", {(c.max.x + 1) * r, (c.max.y + 1) * r, (c.max.z + 1) * r}},
          {"probability", p},
          {"state", c.log_odds >= params.occupied_threshold_log_odds ? "occupied" : "free"}};
}

v1::CellState toProto(map3d::CellState state) {
  switch (state) {
    case map3d::CellState::kFree: return v1::FREE;
    case map3d::CellState::kOccupied: return v1::OCCUPIED;
    case map3d::CellState::kUnknown: break;
  }
  return v1::UNKNOWN;
}

bool isProtobuf(const net::Request& request) {
  const auto type = request.find(http::field::content_type);
  return type != request.end() &&
         std::string_view(type->value().data(), type->value().size()).starts_with(kProtobuf);
}

/// Order of cuboids in paged box answers: by lowest cell, z then y then x.
using CuboidOrder = std::tuple<int32_t, int32_t, int32_t>;
CuboidOrder orderOf(const map3d::CuboidBox& c) { return {c.min.z, c.min.y, c.min.x}; }

std::string pageToken(const CuboidOrder& o) {
  return std::to_string(std::get<0>(o)) + "_" + std::to_string(std::get<1>(o)) + "_" + std::to_string(std::get<2>(o));
}

CuboidOrder parsePageToken(const std::string& token) {
  CuboidOrder o;
  const size_t a = token.find('_');
  const size_t b = a == std::string::npos ? a : token.find('_', a + 1);
  if (b == std::string::npos) throw ApiError(400, "invalid_argument", "page_token is not one this server issued");
  std::get<0>(o) = static_cast<int32_t>(parseInteger(token.substr(0, a), "page_token"));
  std::get<1>(o) = static_cast<int32_t>(parseInteger(token.substr(a + 1, b - a - 1), "page_token"));
  std::get<2>(o) = static_cast<int32_t>(parseInteger(token.substr(b + 1), "page_token"));
  return o;
}

}  // namespace

net::Response HttpApi::occupancy(const net::Request& request, const Target& target, const MapWorker& worker) {
  const Eigen::Vector3d point(target.number("x"), target.number("y"), target.number("z"));
  const map3d::CuboidMap& map = worker.map();
  const map3d::CellQuery q = map.query(point);
  nlohmann::json body{{"state", map3d::toString(q.state)}, {"probability", q.probability}, {"cuboid", nullptr}};
  if (q.state != map3d::CellState::kUnknown) {
    const double r = map.resolution();
    body["cuboid"] = {{"min", {q.cuboid.min.x * r, q.cuboid.min.y * r, q.cuboid.min.z * r}},
                      {"max", {(q.cuboid.max.x + 1) * r, (q.cuboid.max.y + 1) * r, (q.cuboid.max.z + 1) * r}}};
  }
  return jsonResponse(request, body);
}

net::Response HttpApi::occupancyBatch(const net::Request& request, const MapWorker& worker) {
  const map3d::CuboidMap& map = worker.map();
  const size_t max_points = service_.config().limits.max_batch_points;
  if (isProtobuf(request)) {
    v1::OccupancyBatchRequest in;
    if (!in.ParseFromString(request.body())) {
      throw ApiError(400, "invalid_argument", "body is not an rmap.v1.OccupancyBatchRequest");
    }
    if (in.xyz_m_size() % 3 != 0) throw ApiError(400, "invalid_argument", "xyz_m must hold x,y,z triples");
    const size_t n = static_cast<size_t>(in.xyz_m_size()) / 3;
    if (n > max_points) {
      throw ApiError(413, "too_many_points", "at most " + std::to_string(max_points) + " points per batch");
    }
    v1::OccupancyBatchResponse out;
    out.mutable_states()->Reserve(static_cast<int>(n));
    out.mutable_probabilities()->Reserve(static_cast<int>(n));
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d p(in.xyz_m(3 * i), in.xyz_m(3 * i + 1), in.xyz_m(3 * i + 2));
      if (!p.allFinite()) throw ApiError(400, "invalid_argument", "point " + std::to_string(i) + " is not finite");
      const map3d::CellQuery q = map.query(p);
      out.add_states(toProto(q.state));
      out.add_probabilities(static_cast<float>(q.probability));
    }
    return bodyResponse(request, out.SerializeAsString(), kProtobuf);
  }
  nlohmann::json in;
  try {
    in = nlohmann::json::parse(request.body());
  } catch (const nlohmann::json::exception& e) {
    throw ApiError(400, "invalid_argument", std::string("body is not JSON: ") + e.what());
  }
  if (!in.is_object() || !in.contains("points") || !in["points"].is_array()) {
    throw ApiError(400, "invalid_argument", "body must be {\"points\": [[x, y, z], ...]}");
  }
  const nlohmann::json& points = in["points"];
  if (points.size() > max_points) {
    throw ApiError(413, "too_many_points", "at most " + std::to_string(max_points) + " points per batch");
  }
  nlohmann::json states = nlohmann::json::array();
  nlohmann::json probabilities = nlohmann::json::array();
  for (size_t i = 0; i < points.size(); ++i) {
    const nlohmann::json& p = points[i];
    if (!p.is_array() || p.size() != 3 || !p[0].is_number() || !p[1].is_number() || !p[2].is_number()) {
      throw ApiError(400, "invalid_argument", "point " + std::to_string(i) + " must be [x, y, z]");
    }
    const Eigen::Vector3d point(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
    const map3d::CellQuery q = map.query(point);
    states.push_back(map3d::toString(q.state));
    probabilities.push_back(q.probability);
  }
  return jsonResponse(request, {{"states", std::move(states)}, {"probabilities", std::move(probabilities)}});
}

net::Response HttpApi::occupancyBox(const net::Request& request, const Target& target, const MapWorker& worker) {
  const map3d::CuboidMap& map = worker.map();
  const std::array<double, 3> lo = target.vector3("min");
  const std::array<double, 3> hi = target.vector3("max");
  map3d::CellKey min, max;
  for (int a = 0; a < 3; ++a) {
    if (!(lo[a] <= hi[a])) throw ApiError(400, "invalid_argument", "min must not exceed max on any axis");
    min[a] = map.grid().index(lo[a]);
    max[a] = map.grid().index(hi[a]);
  }
  const size_t limit = static_cast<size_t>(
      target.integer("limit", 1000, 1, static_cast<int64_t>(service_.config().limits.max_box_cuboids)));
  const bool paged = target.has("page_token");
  const CuboidOrder after = paged ? parsePageToken(target.text("page_token")) : CuboidOrder{};
  // Keep the `limit` first cuboids after the token: a max-heap on the order.
  const auto later = [](const map3d::CuboidBox& a, const map3d::CuboidBox& b) { return orderOf(a) < orderOf(b); };
  std::priority_queue<map3d::CuboidBox, std::vector<map3d::CuboidBox>, decltype(later)> page(later);
  bool more = false;
  map.forEachCuboid(min, max, [&](const map3d::CuboidBox& c) {
    if (paged && !(after < orderOf(c))) return true;
    page.push(c);
    if (page.size() > limit) {
      page.pop();
      more = true;
    }
    return true;
  });
  std::vector<map3d::CuboidBox> sorted;
  while (!page.empty()) {
    sorted.push_back(page.top());
    page.pop();
  }
  std::reverse(sorted.begin(), sorted.end());
  nlohmann::json cuboids = nlohmann::json::array();
  for (const map3d::CuboidBox& c : sorted) cuboids.push_back(cuboidJson(map.grid(), c, map.occupancyParams()));
  nlohmann::json body{{"cuboids", std::move(cuboids)}, {"next_page_token", nullptr}};
  if (more) body["next_page_token"] = pageToken(orderOf(sorted.back()));
  return jsonResponse(request, body);
}

net::Response HttpApi::tileset(const net::Request& request, MapWorker& worker) {
  const map3d::CuboidMap& map = worker.map();
  nlohmann::json levels = nlohmann::json::array();
  for (int level = 0; level < kTileLevels; ++level) {
    nlohmann::json tiles = nlohmann::json::array();
    for (const TileVersion& t : worker.tiles().tiles(level)) tiles.push_back({t.key.x, t.key.y, t.key.z, t.version});
    const double cell_m = map.resolution() * static_cast<double>(1 << level);
    levels.push_back({{"level", level},
                      {"cell_m", cell_m},
                      {"tile_edge_m", cell_m * kTileEdgeCells},
                      {"tiles", std::move(tiles)}});
  }
  return jsonResponse(request, {{"map", worker.name()},
                                {"resolution_m", map.resolution()},
                                {"tile_edge_cells", kTileEdgeCells},
                                {"epoch", service_.epoch()},
                                {"map_version", worker.tiles().mapVersion()},
                                {"levels", std::move(levels)}});
}

net::Response HttpApi::tile(const net::Request& request, const Target& target, MapWorker& worker) {
  const std::vector<std::string>& s = target.segments;
  const int64_t level = parseInteger(s[4], "tile level");
  if (level < 0 || level >= kTileLevels) {
    throw ApiError(400, "invalid_argument", "tile level must be in [0, " + std::to_string(kTileLevels - 1) + "]");
  }
  TileKey key{static_cast<int>(level), 0, 0, 0};
  int32_t* xyz[3] = {&key.x, &key.y, &key.z};
  const int64_t reach = (int64_t{2} * map3d::kCellLimit) / tileEdgeBaseCells(key.level) + 1;
  for (int a = 0; a < 3; ++a) {
    const int64_t v = parseInteger(s[5 + a], "tile coordinate");
    if (v < -reach || v > reach) throw ApiError(400, "invalid_argument", "tile coordinate out of the map's range");
    *xyz[a] = static_cast<int32_t>(v);
  }
  const uint64_t version = worker.tiles().version(key).value_or(0);
  const bool json = acceptsJson(request);
  // Versions restart with every start of the server; the epoch keeps ETags of different starts apart.
  const std::string etag =
      "\"" + std::to_string(service_.epoch()) + "-" + std::to_string(version) + (json ? "j" : "p") + "\"";
  if (etagMatches(request, etag)) return notModified(request, etag);
  const map3d::CuboidMap& map = worker.map();
  const std::vector<map3d::CuboidBox> cuboids = tileCuboids(map, key);
  net::Response response;
  if (json) {
    nlohmann::json list = nlohmann::json::array();
    for (const map3d::CuboidBox& c : cuboids) {
      list.push_back({{"min_cell", {c.min.x, c.min.y, c.min.z}},
                      {"max_cell", {c.max.x, c.max.y, c.max.z}},
                      {"probability", map3d::probability(c.log_odds)}});
    }
    response = jsonResponse(request, {{"level", key.level}, {"x", key.x}, {"y", key.y}, {"z", key.z},
                                      {"epoch", service_.epoch()}, {"version", version},
                                      {"resolution_m", map.resolution()}, {"cuboids", std::move(list)}});
  } else {
    v1::Tile out;
    out.set_level(static_cast<uint32_t>(key.level));
    out.set_x(key.x);
    out.set_y(key.y);
    out.set_z(key.z);
    out.set_epoch(static_cast<uint64_t>(service_.epoch()));
    out.set_version(version);
    out.set_resolution_m(map.resolution());
    for (const map3d::CuboidBox& c : cuboids) {
      for (int a = 0; a < 3; ++a) {
        out.add_min_cell(c.min[a]);
        out.add_max_cell(c.max[a]);
      }
      out.add_probability(static_cast<float>(map3d::probability(c.log_odds)));
    }
    response = bodyResponse(request, out.SerializeAsString(), kProtobuf);
  }
  response.set(http::field::etag, etag);
  response.set(http::field::cache_control, "no-cache");
  return response;
}

}  // namespace rmap::app
