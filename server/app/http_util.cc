#include "app/http_util.h"

#include <charconv>
#include <cmath>

namespace rmap::app {

namespace http = boost::beast::http;

namespace {

int hexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::string percentDecode(std::string_view text, bool plus_is_space) {
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '%') {
      const int hi = i + 2 < text.size() ? hexValue(text[i + 1]) : -1;
      const int lo = i + 2 < text.size() ? hexValue(text[i + 2]) : -1;
      if (hi < 0 || lo < 0) throw ApiError(400, "invalid_argument", "bad percent-encoding in the request target");
      out.push_back(static_cast<char>(hi * 16 + lo));
      i += 2;
    } else {
      out.push_back(plus_is_space && c == '+' ? ' ' : c);
    }
  }
  return out;
}

bool parseDouble(const std::string& text, double& value) {
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  return ec == std::errc() && ptr == end && std::isfinite(value);
}

}  // namespace

Target Target::parse(std::string_view target) {
  Target out;
  const size_t question = target.find('?');
  std::string_view path = target.substr(0, question);
  while (!path.empty()) {
    const size_t slash = path.find('/');
    const std::string_view segment = path.substr(0, slash);
    if (!segment.empty()) out.segments.push_back(percentDecode(segment, false));
    if (slash == std::string_view::npos) break;
    path.remove_prefix(slash + 1);
  }
  if (question == std::string_view::npos) return out;
  std::string_view query = target.substr(question + 1);
  while (!query.empty()) {
    const size_t amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    if (!pair.empty()) {
      const size_t eq = pair.find('=');
      out.query[percentDecode(pair.substr(0, eq), true)] =
          eq == std::string_view::npos ? std::string() : percentDecode(pair.substr(eq + 1), true);
    }
    if (amp == std::string_view::npos) break;
    query.remove_prefix(amp + 1);
  }
  return out;
}

double Target::number(const std::string& key) const {
  const auto it = query.find(key);
  if (it == query.end()) throw ApiError(400, "invalid_argument", "query parameter '" + key + "' is required");
  double value = 0.0;
  if (!parseDouble(it->second, value)) {
    throw ApiError(400, "invalid_argument", "query parameter '" + key + "' must be a finite number");
  }
  return value;
}

int64_t Target::integer(const std::string& key, int64_t fallback, int64_t min, int64_t max) const {
  const auto it = query.find(key);
  if (it == query.end()) return fallback;
  const int64_t value = parseInteger(it->second, key.c_str());
  if (value < min || value > max) {
    throw ApiError(400, "invalid_argument",
                   "query parameter '" + key + "' must be in [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  }
  return value;
}

std::array<double, 3> Target::vector3(const std::string& key) const {
  const auto it = query.find(key);
  if (it == query.end()) throw ApiError(400, "invalid_argument", "query parameter '" + key + "' is required");
  std::array<double, 3> v{};
  std::string_view text = it->second;
  for (int a = 0; a < 3; ++a) {
    const size_t comma = text.find(',');
    if ((a < 2) == (comma == std::string_view::npos) || !parseDouble(std::string(text.substr(0, comma)), v[a])) {
      throw ApiError(400, "invalid_argument", "query parameter '" + key + "' must be three finite numbers x,y,z");
    }
    if (comma != std::string_view::npos) text.remove_prefix(comma + 1);
  }
  return v;
}

std::string Target::text(const std::string& key, const std::string& fallback) const {
  const auto it = query.find(key);
  return it == query.end() ? fallback : it->second;
}

int64_t parseInteger(const std::string& text, const char* what) {
  int64_t value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (text.empty() || ec != std::errc() || ptr != end) {
    throw ApiError(400, "invalid_argument", std::string(what) + " must be an integer, not '" + text + "'");
  }
  return value;
}

net::Response bodyResponse(const net::Request& request, std::string body, const std::string& content_type,
                           int status) {
  net::Response response{static_cast<http::status>(status), request.version()};
  response.set(http::field::content_type, content_type);
  response.keep_alive(request.keep_alive());
  response.body() = std::move(body);
  response.prepare_payload();
  return response;
}

net::Response jsonResponse(const net::Request& request, const nlohmann::json& body, int status) {
  return bodyResponse(request, body.dump(), "application/json", status);
}

bool acceptsJson(const net::Request& request) {
  const auto accept = request.find(http::field::accept);
  return accept != request.end() &&
         std::string_view(accept->value().data(), accept->value().size()).find("application/json") !=
             std::string_view::npos;
}

bool etagMatches(const net::Request& request, std::string_view etag) {
  const auto [first, last] = request.equal_range(http::field::if_none_match);
  for (auto field = first; field != last; ++field) {
    std::string_view list(field->value().data(), field->value().size());
    while (!list.empty()) {
      const size_t comma = list.find(',');
      std::string_view tag = list.substr(0, comma);
      while (!tag.empty() && (tag.front() == ' ' || tag.front() == '\t')) tag.remove_prefix(1);
      while (!tag.empty() && (tag.back() == ' ' || tag.back() == '\t')) tag.remove_suffix(1);
      if (tag.starts_with("W/")) tag.remove_prefix(2);
      if (tag == "*" || tag == etag) return true;
      if (comma == std::string_view::npos) break;
      list.remove_prefix(comma + 1);
    }
  }
  return false;
}

net::Response notModified(const net::Request& request, const std::string& etag) {
  net::Response response{http::status::not_modified, request.version()};
  response.set(http::field::etag, etag);
  response.set(http::field::cache_control, "no-cache");
  response.keep_alive(request.keep_alive());
  response.prepare_payload();
  return response;
}

}  // namespace rmap::app
