#pragma once
/// @file http_util.h
/// Small pieces the HTTP handlers share: the target split into path segments
/// and query parameters, typed parameter parsing with clear errors, JSON and
/// text responses.

#include <map>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "net/service.h"

namespace rmap::app {

/// A request that cannot be answered: becomes a JSON error with this status.
class ApiError : public std::runtime_error {
 public:
  ApiError(int status, std::string code, const std::string& message)
      : std::runtime_error(message), status_(status), code_(std::move(code)) {}
  /// 405 for `method` on a route that serves only `allowed` (e.g. "GET").
  static ApiError methodNotAllowed(std::string_view method, std::string allowed) {
    ApiError e(405, "method_not_allowed", std::string(method) + " is not allowed here; use " + allowed);
    e.allow_ = std::move(allowed);
    return e;
  }
  int status() const { return status_; }
  const std::string& code() const { return code_; }
  /// Value of the Allow header (405 only), else empty.
  const std::string& allow() const { return allow_; }

 private:
  int status_;
  std::string code_;
  std::string allow_;
};

/// Path segments (percent-decoded) and query parameters of a request target.
struct Target {
  std::vector<std::string> segments;
  std::map<std::string, std::string> query;

  /// @throws ApiError 400 for bad percent-encoding
  static Target parse(std::string_view target);
  bool has(const std::string& key) const { return query.count(key) > 0; }
  /// @throws ApiError 400 naming the parameter when missing or not a finite number
  double number(const std::string& key) const;
  /// Integer parameter within [min, max], `fallback` when absent.
  /// @throws ApiError 400 naming the parameter when malformed or out of range
  int64_t integer(const std::string& key, int64_t fallback, int64_t min, int64_t max) const;
  /// "x,y,z" parameter. @throws ApiError 400
  std::array<double, 3> vector3(const std::string& key) const;
  std::string text(const std::string& key, const std::string& fallback = {}) const;
};

/// Parses a decimal integer segment. @throws ApiError 400 naming `what`
int64_t parseInteger(const std::string& text, const char* what);

net::Response jsonResponse(const net::Request& request, const nlohmann::json& body, int status = 200);
net::Response bodyResponse(const net::Request& request, std::string body, const std::string& content_type,
                           int status = 200);
/// Whether the client asked for JSON (Accept: application/json).
bool acceptsJson(const net::Request& request);

/// Whether the request's If-None-Match names `etag` (a strong tag): "*", or a
/// comma-separated list compared weakly (a W/ prefix is ignored), RFC 9110 §13.1.2.
bool etagMatches(const net::Request& request, std::string_view etag);
/// 304 Not Modified: no body, the ETag, Cache-Control: no-cache (every
/// validated response of rmapd is no-cache).
net::Response notModified(const net::Request& request, const std::string& etag);

}  // namespace rmap::app
