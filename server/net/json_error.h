#pragma once
/// @file json_error.h
/// The one error shape of the HTTP API: {"error": {"code": "...", "message": "..."}}.

#include <string>

#include "net/service.h"

namespace rmap::net {

/// A JSON error response with the given status; keep-alive follows `request`
/// when given.
Response jsonError(boost::beast::http::status status, const std::string& code, const std::string& message,
                   unsigned http_version = 11, bool keep_alive = false);

}  // namespace rmap::net
