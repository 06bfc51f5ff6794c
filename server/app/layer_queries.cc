// 2D layer queries of the HTTP API: the layers' description, raster tiles, map_server export.
#include "app/grid2d_export.h"
#include "app/http_api.h"
#include "app/image_codecs.h"
#include "app/layer_tiles.h"

namespace rmap::app {

namespace http = boost::beast::http;

namespace {

/// @throws ApiError 404 layer_not_found when the map's SLAM has taken no scan
const Slam2dLayer& layerOf(const MapWorker& worker) {
  const Slam2dLayer& slam = worker.slam2d();
  if (!slam.hasLayer()) {
    throw ApiError(404, "layer_not_found", "map '" + worker.name() + "' has no 2D layer (it got no laser scans)");
  }
  return slam;
}

/// ETag of a 2D product: epoch (versions restart with each start), SLAM map version, product.
std::string layerEtag(int64_t epoch, uint64_t version, const char* product) {
  // Quotes added last: GCC 12 warns falsely (-Wrestrict, bug 105329) on `"\"" + std::to_string(…)`.
  return '"' + (std::to_string(epoch) + "-" + std::to_string(version) + "-" + product) + '"';
}

/// Answers a 2D product: 304 when the client holds this version, else the body made under the read lock.
template <typename Make>
net::Response layerResponse(const net::Request& request, int64_t epoch, const Slam2dLayer& slam,
                            const char* product, const char* content_type, Make&& make) {
  if (const std::string etag = layerEtag(epoch, slam.version(), product); etagMatches(request, etag)) {
    return notModified(request, etag);
  }
  uint64_t version = 0;
  std::string body = slam.read([&](const Grid2dSource& grid) {
    version = slam.version();  // exact: the writer changes it under the exclusive lock
    return make(grid);
  });
  net::Response response = bodyResponse(request, std::move(body), content_type);
  response.set(http::field::etag, layerEtag(epoch, version, product));
  response.set(http::field::cache_control, "no-cache");
  return response;
}

/// Pixels of a whole-layer image at most: 8192 × 8192 cells (410 m square at 0.05 m), 128 MiB of pixels.
constexpr size_t kMaxLayerImagePixels = size_t{1} << 26;

}  // namespace

net::Response HttpApi::layers(const net::Request& request, const MapWorker& worker) {
  const Slam2dLayer& slam = layerOf(worker);
  nlohmann::json body = slam.read([&](const Grid2dSource& grid) {
    const double r = grid.resolutionM();
    const double half_m = static_cast<double>(kLayerExtentCells) * r / 2;
    const Eigen::AlignedBox2i known = grid.knownCells();
    nlohmann::json bounds = nullptr;
    if (!known.isEmpty()) {
      bounds = {{"min", {known.min().x() * r, known.min().y() * r}},
                {"max", {(known.max().x() + 1) * r, (known.max().y() + 1) * r}}};
    }
    return nlohmann::json{{"map", worker.name()},
                          {"epoch", service_.epoch()},
                          {"version", slam.version()},
                          {"scans", slam.scans()},
                          {"resolution_m", r},
                          {"layers", {"occupancy", "reflectivity"}},
                          {"tile_px", kLayerTilePx},
                          {"min_zoom", 0},
                          {"native_zoom", kLayerNativeZoom},
                          {"max_zoom", kLayerMaxZoom},
                          {"extent_min_m", {-half_m, -half_m}},
                          {"extent_max_m", {half_m, half_m}},
                          {"known_bounds", std::move(bounds)},
                          {"tiles", "/v1/maps/" + worker.name() + "/layers/{layer}/{z}/{x}/{y}.png"}};
  });
  return jsonResponse(request, body);
}

net::Response HttpApi::layerTile(const net::Request& request, const Target& target, const MapWorker& worker) {
  const std::vector<std::string>& s = target.segments;
  const std::optional<Layer2d> layer = parseLayer2d(s[4]);
  if (!layer) throw ApiError(404, "not_found", "no layer '" + s[4] + "'; the layers are occupancy and reflectivity");
  if (!s[7].ends_with(".png")) throw ApiError(400, "invalid_argument", "layer tile y must be '<integer>.png'");
  LayerTileKey key;
  const int64_t z = parseInteger(s[5], "layer tile z");
  if (z < 0 || z > kLayerMaxZoom) {
    throw ApiError(400, "invalid_argument", "layer tile z must be in [0, " + std::to_string(kLayerMaxZoom) + "]");
  }
  key.z = static_cast<int>(z);
  key.x = parseInteger(s[6], "layer tile x");
  key.y = parseInteger(s[7].substr(0, s[7].size() - 4), "layer tile y");
  checkLayerTile(key);  // std::invalid_argument: 400
  const Slam2dLayer& slam = layerOf(worker);
  const char* product = *layer == Layer2d::kOccupancy ? "occupancy" : "reflectivity";
  return layerResponse(request, service_.epoch(), slam, product, "image/png",
                       [&](const Grid2dSource& grid) { return encodePng(renderLayerTile(grid, *layer, key)); });
}

net::Response HttpApi::layerImage(const net::Request& request, const std::string& file, const MapWorker& worker) {
  const std::optional<Layer2d> layer =
      file.ends_with(".png") ? parseLayer2d(std::string_view(file).substr(0, file.size() - 4)) : std::nullopt;
  if (!layer) {
    throw ApiError(404, "not_found", "no layer image '" + file + "'; there are occupancy.png and reflectivity.png");
  }
  const Slam2dLayer& slam = layerOf(worker);
  const std::string product = std::string(toString(*layer)) + "-image";
  try {
    return layerResponse(request, service_.epoch(), slam, product.c_str(), "image/png", [&](const Grid2dSource& grid) {
      return encodePng(renderLayerImage(grid, *layer, kMaxLayerImagePixels));
    });
  } catch (const std::length_error& e) {
    throw ApiError(413, "image_too_large", e.what());
  }
}

net::Response HttpApi::gridPgm(const net::Request& request, const MapWorker& worker) {
  return layerResponse(request, service_.epoch(), layerOf(worker), "pgm", "image/x-portable-graymap",
                       [](const Grid2dSource& grid) { return exportGridPgm(grid); });
}

net::Response HttpApi::gridYaml(const net::Request& request, const MapWorker& worker) {
  return layerResponse(request, service_.epoch(), layerOf(worker), "yaml", "application/yaml",
                       [](const Grid2dSource& grid) { return exportGridYaml(grid, "grid2d.pgm"); });
}

}  // namespace rmap::app
