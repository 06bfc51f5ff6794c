// Whole-map transfer of the HTTP API: the 3D map out as an OctoMap `.bt`, an OctoMap (`.bt`
// or `.ot`) in as a map's 3D content.
#include <cmath>
#include <stdexcept>

#include "app/http_api.h"
#include "app/ingest.h"
#include "map3d/octomap_interop.h"
#include "store/store.h"

namespace rmap::app {

namespace http = boost::beast::http;

namespace {

/// A parsed OctoMap body: its leaves with log-odds, and what it was.
struct OctreeBody {
  const char* format;  ///< "bt" or "ot"
  std::string tree_id;
  double resolution_m = 0.0;
  std::vector<map3d::OctreeLeaf> leaves;
};

/// @throws ApiError 400 for a body that is neither format or does not parse
OctreeBody parseOctree(const std::string& body, const map3d::OccupancyParams& occupancy) {
  try {
    if (map3d::looksLikeBt(body)) {
      const map3d::BtTree tree = map3d::parseBt(body);
      return {"bt", "OcTree", tree.resolution_m, map3d::leavesOf(tree, occupancy)};
    }
    if (map3d::looksLikeOt(body)) {
      map3d::OtTree tree = map3d::parseOt(body);
      return {"ot", tree.id, tree.resolution_m, std::move(tree.leaves)};
    }
  } catch (const std::runtime_error& e) {
    throw ApiError(400, "invalid_argument", std::string("body is not a valid OctoMap file: ") + e.what());
  }
  throw ApiError(400, "invalid_argument",
                 "body is not an OctoMap file: the first line must start with \"# Octomap OcTree binary file\" "
                 "(.bt) or \"# Octomap OcTree file\" (.ot)");
}

bool sameResolution(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(a, b); }

}  // namespace

net::Response HttpApi::exportBt(const net::Request& request, const MapWorker& map) {
  net::Response response = bodyResponse(request, map3d::mapToBt(map.map()), "application/octet-stream");
  response.set(http::field::content_disposition, "attachment; filename=\"" + map.name() + ".bt\"");
  return response;
}

net::Response HttpApi::importMap(const net::Request& request, const Target& target, const std::string& name) {
  if (!validName(name)) throw ApiError(400, "invalid_argument", "map must be 1..64 characters of [A-Za-z0-9._-]");
  const std::string replace_text = target.text("replace", "false");
  if (replace_text != "true" && replace_text != "false") {
    throw ApiError(400, "invalid_argument", "replace must be true or false, not '" + replace_text + "'");
  }
  const bool replace = replace_text == "true";
  if (service_.memoryBound().exceeded()) {
    service_.metrics().imports_refused_memory.fetch_add(1, std::memory_order_relaxed);
    throw ApiError(503, "resource_exhausted", service_.memoryBound().describe() + "; nothing was imported, retry later");
  }
  std::shared_ptr<MapWorker> worker = service_.findMap(name);
  // An existing map keeps its parameters; a new one takes the configured ones.
  const map3d::OccupancyParams occupancy = worker ? worker->map().occupancyParams() : service_.config().maps.occupancy;
  const map3d::FusionParams fusion = worker ? worker->map().fusionParams() : service_.config().maps.fusion;
  const OctreeBody tree = parseOctree(request.body(), occupancy);
  if (!(tree.resolution_m >= kMinResolution_m && tree.resolution_m <= kMaxResolution_m)) {
    throw ApiError(400, "invalid_argument",
                   "the tree's resolution " + std::to_string(tree.resolution_m) + " m is outside [0.005, 10] m");
  }
  const auto checkResolution = [&](const MapWorker& map) {
    if (!sameResolution(map.map().resolution(), tree.resolution_m)) {
      throw ApiError(409, "resolution_mismatch",
                     "map '" + name + "' has cells of " + std::to_string(map.map().resolution()) +
                         " m, the tree " + std::to_string(tree.resolution_m) + " m; import into a new map");
    }
  };
  if (worker) checkResolution(*worker);
  map3d::MapBlocks blocks;
  try {
    blocks = map3d::blocksFromLeaves(tree.leaves, occupancy, fusion, service_.config().limits.max_import_blocks);
  } catch (const std::length_error& e) {
    throw ApiError(413, "import_too_large",
                   std::string(e.what()) + " (limits.max_import_blocks); the map would not fit in memory");
  } catch (const std::invalid_argument& e) {
    throw ApiError(400, "invalid_argument", std::string("body is not a valid OctoMap file: ") + e.what());
  }
  const bool created = !worker;
  try {
    if (created) {
      worker = service_.openMap(name, tree.resolution_m);
      checkResolution(*worker);  // a robot may have created it meanwhile
    }
    if (!worker->importBlocks(blocks, replace)) {
      throw ApiError(409, "map_not_empty",
                     "map '" + name + "' already holds " + std::to_string(worker->map().stats().known_cells) +
                         " known cells; replace its 3D content with replace=true (rmap import --replace)");
    }
  } catch (const store::StoreError& e) {
    throw ApiError(503, "unavailable", std::string("the import could not be stored: ") + e.what());
  }
  return jsonResponse(request, {{"map", mapJson(*worker)},
                                {"created", created},
                                {"format", tree.format},
                                {"tree_id", tree.tree_id},
                                {"leaves", tree.leaves.size()},
                                {"blocks", blocks.size()}});
}

}  // namespace rmap::app
