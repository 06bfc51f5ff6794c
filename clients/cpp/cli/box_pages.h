#pragma once
/// @file box_pages.h
/// Every cuboid of a box query (GET /v1/maps/{map}/occupancy/box), page
/// after page, following next_page_token.

#include <nlohmann/json.hpp>

#include <array>
#include <functional>
#include <string>

#include "client/http_client.h"

namespace rmap::cli {

/// Calls fn with each cuboid object of the answer (min, max, probability, state), in the
/// server's order. Pages are read from the live map (a map that changes meanwhile may
/// repeat or miss cuboids, docs/API.md §6.7).
/// @param map_path   "/v1/maps/<map>"
/// @param page_size  cuboids per request, 1 … the server's limits.max_box_cuboids
/// @return the number of cuboids
/// @throws CommandError for an error answer, client::ClientError for a failed connection
size_t forEachBoxCuboid(client::HttpClient& http, const std::string& map_path, const std::array<double, 3>& min_m,
                        const std::array<double, 3>& max_m, size_t page_size,
                        const std::function<void(const nlohmann::json&)>& fn);

/// Shortest text that reads back as the same double.
std::string numberText(double value);

}  // namespace rmap::cli
