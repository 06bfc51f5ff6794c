#include "net/json_error.h"

#include <nlohmann/json.hpp>

namespace rmap::net {

Response jsonError(boost::beast::http::status status, const std::string& code, const std::string& message,
                   unsigned http_version, bool keep_alive) {
  namespace http = boost::beast::http;
  Response response{status, http_version};
  response.set(http::field::content_type, "application/json");
  response.keep_alive(keep_alive);
  const nlohmann::json body = {{"error", {{"code", code}, {"message", message}}}};
  // Messages may quote client input: replace invalid UTF-8 instead of throwing.
  response.body() = body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  response.prepare_payload();
  return response;
}

Response internalError(unsigned http_version, bool keep_alive) {
  return jsonError(boost::beast::http::status::internal_server_error, "internal_error", "internal server error",
                   http_version, keep_alive);
}

}  // namespace rmap::net
