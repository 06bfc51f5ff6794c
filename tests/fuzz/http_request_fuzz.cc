// Fuzz target: the bytes of an HTTP/1.1 connection as rmapd reads them
// (net/http_session.cc): Beast's request parser with the server's header and
// body limits, headerError on each header, handshakeError on upgrades, then
// what the API does with a request before it reaches the maps (app/http_api.cc):
// authentication and Origin, the target split into segments and query
// parameters, the typed parameter parsers, If-None-Match, and the JSON error
// that answers an ApiError (its text quotes the request).
#include <boost/beast/http/parser.hpp>
#include <boost/beast/websocket/rfc6455.hpp>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>

#include "app/auth.h"
#include "app/http_util.h"
#include "net/header_checks.h"
#include "net/json_error.h"
#include "net/server.h"
#include "net/ws_handshake.h"

namespace {

namespace http = boost::beast::http;
using rmap::app::ApiError;
using rmap::app::Target;

const rmap::app::Authenticator& tokenAuth() {
  static const rmap::app::Authenticator auth(rmap::app::AuthConfig{
      {{"robot-token-1", rmap::app::Role::kRobot, "bot-1"},
       {"viewer-token-1", rmap::app::Role::kViewer, {}},
       {"admin-token-1", rmap::app::Role::kAdmin, {}}},
      {"https://viewer.example"}});
  return auth;
}

void serveApi(const rmap::net::Request& request) {
  const rmap::net::Peer lan{"192.168.1.20", 40000, false};
  tokenAuth().authenticate(request, lan);
  tokenAuth().originAllowed(request);
  static const rmap::app::Authenticator loopback_only(rmap::app::AuthConfig{});
  loopback_only.authenticate(request, lan);
  try {
    const Target target = Target::parse(std::string_view(request.target().data(), request.target().size()));
    for (const auto& [key, value] : target.query) {
      // Every parser on every parameter: each must either parse or throw ApiError.
      try {
        target.number(key);
      } catch (const ApiError&) {
      }
      try {
        target.integer(key, 0, -1000, 1000);
      } catch (const ApiError&) {
      }
      try {
        target.vector3(key);
      } catch (const ApiError&) {
      }
    }
    for (const std::string& segment : target.segments) {
      try {
        rmap::app::parseInteger(segment, "tile coordinate");
      } catch (const ApiError&) {
      }
    }
    target.number("x");  // a required parameter: throws when absent
  } catch (const ApiError& e) {
    const rmap::net::Response error = rmap::net::jsonError(static_cast<http::status>(e.status()), e.code(), e.what(),
                                                           request.version(), request.keep_alive());
    if (error.body().empty()) __builtin_trap();
  }
  rmap::app::etagMatches(request, "\"42\"");
  rmap::app::acceptsJson(request);
}

void serveUpgrade(const rmap::net::Request& request) {
  if (rmap::net::handshakeError(request)) return;
  rmap::net::offersSubprotocol(request, "rmap.v1");
  rmap::app::tokenFromSubprotocols(request);
  tokenAuth().authenticate(request, rmap::net::Peer{"127.0.0.1", 40000, true});
  tokenAuth().originAllowed(request);
}

/// One request from the front of `bytes`; false when the connection would close.
bool readRequest(boost::asio::const_buffer& bytes) {
  const rmap::net::ServerOptions options;
  http::request_parser<http::string_body> parser;
  parser.header_limit(static_cast<std::uint32_t>(options.max_header_bytes));
  parser.body_limit(options.max_body_bytes);
  bool header_checked = false;
  while (!parser.is_done()) {
    boost::beast::error_code ec;
    const size_t used = parser.put(bytes, ec);
    bytes += used;
    if (ec) return false;  // a parse error or, at the end of the bytes, need_more: the session closes
    if (parser.is_header_done() && !header_checked) {
      header_checked = true;
      if (rmap::net::headerError(parser.get(), parser.chunked())) return false;
    }
    if (used == 0 && !parser.is_done()) return false;
  }
  const rmap::net::Request& request = parser.get();
  if (boost::beast::websocket::is_upgrade(request)) {
    serveUpgrade(request);
    return false;  // the connection leaves HTTP
  }
  serveApi(request);
  return request.keep_alive();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  boost::asio::const_buffer bytes(data, size);
  // Pipelined requests, as a kept-alive connection reads them.
  for (int request = 0; request < 16 && bytes.size() > 0; ++request) {
    if (!readRequest(bytes)) break;
  }
  return 0;
}
