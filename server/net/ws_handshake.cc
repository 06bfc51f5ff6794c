#include "net/ws_handshake.h"

#include <boost/beast/http/field.hpp>
#include <algorithm>

#include "net/json_error.h"

namespace rmap::net {
namespace {

namespace http = boost::beast::http;

std::string_view trim(std::string_view s) {
  const auto is_space = [](char c) { return c == ' ' || c == '\t'; };
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

bool isBase64Digit(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '+' || c == '/';
}

/// 16 bytes in base64: 22 digits and the "==" padding.
bool isNonce(std::string_view key) {
  return key.size() == 24 && key.substr(22) == "==" && std::all_of(key.begin(), key.begin() + 22, isBase64Digit);
}

}  // namespace

std::vector<std::string_view> offeredSubprotocols(const Request& request) {
  std::vector<std::string_view> offered;
  const auto [first, last] = request.equal_range(http::field::sec_websocket_protocol);
  for (auto field = first; field != last; ++field) {
    std::string_view list(field->value().data(), field->value().size());
    while (true) {
      const size_t comma = list.find(',');
      if (const std::string_view item = trim(list.substr(0, comma)); !item.empty()) offered.push_back(item);
      if (comma == std::string_view::npos) break;
      list.remove_prefix(comma + 1);
    }
  }
  return offered;
}

bool offersSubprotocol(const Request& request, std::string_view name) {
  const auto offered = offeredSubprotocols(request);
  return std::find(offered.begin(), offered.end(), name) != offered.end();
}

std::optional<Response> handshakeError(const Request& request) {
  const auto key = request.find(http::field::sec_websocket_key);
  if (key == request.end() || !isNonce(std::string_view(key->value().data(), key->value().size()))) {
    return jsonError(http::status::bad_request, "bad_request", "Sec-WebSocket-Key must be 16 bytes in base64",
                     request.version());
  }
  if (request[http::field::sec_websocket_version] != "13") {
    Response response = jsonError(http::status::upgrade_required, "unsupported_websocket_version",
                                  "only WebSocket version 13 is supported", request.version());
    response.set(http::field::sec_websocket_version, "13");
    return response;
  }
  return std::nullopt;
}

}  // namespace rmap::net
