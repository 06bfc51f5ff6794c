#pragma once
/// @file json_error.h
/// The one error shape of the HTTP API: {"error": {"code": "...", "message": "..."}}.

#include <string>

#include "net/service.h"

namespace rmap::net {

/// A JSON error response with the given status, HTTP version and keep-alive;
/// Content-Type application/json, Content-Length set. Invalid UTF-8 in
/// `message` is replaced (U+FFFD) rather than rejected.
Response jsonError(boost::beast::http::status status, const std::string& code, const std::string& message,
                   unsigned http_version = 11, bool keep_alive = false);

/// The one 500 of the server: code "internal_error", a fixed message. What
/// went wrong belongs in the log, never in a response (it may name files or SQL).
Response internalError(unsigned http_version = 11, bool keep_alive = false);

}  // namespace rmap::net
