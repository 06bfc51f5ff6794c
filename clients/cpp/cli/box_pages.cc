#include "cli/box_pages.h"

#include <cctype>
#include <charconv>
#include <cstdio>

#include "cli/map_server.h"

namespace rmap::cli {

namespace {

std::string vectorText(const std::array<double, 3>& v) {
  return numberText(v[0]) + "," + numberText(v[1]) + "," + numberText(v[2]);
}

/// Percent-encodes everything but RFC 3986's unreserved characters.
std::string queryValue(const std::string& text) {
  std::string out;
  for (const unsigned char c : text) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~') {
      out += static_cast<char>(c);
    } else {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", c);
      out += hex;
    }
  }
  return out;
}

}  // namespace

std::string numberText(double value) {
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, value).ptr;
  return std::string(buffer, end);
}

size_t forEachBoxCuboid(client::HttpClient& http, const std::string& map_path, const std::array<double, 3>& min_m,
                        const std::array<double, 3>& max_m, size_t page_size,
                        const std::function<void(const nlohmann::json&)>& fn) {
  const std::string first = map_path + "/occupancy/box?min=" + vectorText(min_m) + "&max=" + vectorText(max_m) +
                            "&limit=" + std::to_string(page_size);
  size_t count = 0;
  std::string token;
  do {
    const std::string target = token.empty() ? first : first + "&page_token=" + queryValue(token);
    const client::HttpResponse& r = requireOk(http.get(target), "box query");
    const nlohmann::json page = nlohmann::json::parse(r.body, nullptr, false);
    if (!page.is_object() || !page.contains("cuboids") || !page["cuboids"].is_array()) {
      throw CommandError("box query: the server's answer is not a page of cuboids");
    }
    for (const nlohmann::json& cuboid : page["cuboids"]) {
      fn(cuboid);
      ++count;
    }
    const auto next = page.find("next_page_token");
    token = next != page.end() && next->is_string() ? next->get<std::string>() : std::string();
  } while (!token.empty());
  return count;
}

}  // namespace rmap::cli
