#pragma once
/// @file http_api.h
/// The HTTP API (docs/API.md): routes a request to the viewer's static files
/// or, after authentication, to its handler, turns ApiError into the JSON
/// error shape and counts requests. Handlers are thin: the work is done by
/// MappingService, the maps and the store.

#include "app/auth.h"
#include "app/http_util.h"
#include "app/mapping_service.h"
#include "app/static_files.h"
#include "net/service.h"

namespace rmap::app {

class HttpApi {
 public:
  HttpApi(MappingService& service, const Authenticator& auth);

  net::Response handle(net::Request& request, const net::Peer& peer);

 private:
  net::Response route(net::Request& request, const net::Peer& peer, const Target& target);
  net::Response health(const net::Request& request);
  net::Response metrics(const net::Request& request);
  net::Response listMaps(const net::Request& request);
  net::Response describeMap(const net::Request& request, const MapWorker& map);
  net::Response listRobots(const net::Request& request);
  net::Response describeRobot(const net::Request& request, const std::string& robot_id);
  net::Response trajectory(const net::Request& request, const Target& target, const std::string& robot_id);
  net::Response loopClosures(const net::Request& request, const Target& target);
  // Map queries (map_queries.cc).
  net::Response occupancy(const net::Request& request, const Target& target, const MapWorker& map);
  net::Response occupancyBatch(const net::Request& request, const MapWorker& map);
  net::Response occupancyBox(const net::Request& request, const Target& target, const MapWorker& map);
  net::Response tileset(const net::Request& request, MapWorker& map);
  net::Response tile(const net::Request& request, const Target& target, MapWorker& map);
  // 2D layers (layer_queries.cc).
  net::Response layers(const net::Request& request, const MapWorker& map);
  net::Response layerTile(const net::Request& request, const Target& target, const MapWorker& map);
  net::Response gridPgm(const net::Request& request, const MapWorker& map);
  net::Response gridYaml(const net::Request& request, const MapWorker& map);
  net::Response layerImage(const net::Request& request, const std::string& file, const MapWorker& map);
  // Whole-map transfer (map_transfer.cc).
  net::Response exportBt(const net::Request& request, const MapWorker& map);
  /// POST /v1/maps/{name}:import; creates the map when missing.
  net::Response importMap(const net::Request& request, const Target& target, const std::string& name);

  MappingService& service_;
  const Authenticator& auth_;
  StaticFiles static_files_;  ///< from service.config().web_root
};

/// JSON of a map's description (GET /v1/maps/{map}).
nlohmann::json mapJson(const MapWorker& map);

}  // namespace rmap::app
