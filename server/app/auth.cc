#include "app/auth.h"

#include <boost/beast/core/string.hpp>
#include <boost/beast/http/field.hpp>

#include <algorithm>

#include "net/ws_handshake.h"

namespace rmap::app {

namespace http = boost::beast::http;

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

/// Compares without an early exit so response timing does not leak how much of a token matched.
bool sameToken(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

}  // namespace

std::optional<std::string> tokenFromSubprotocols(const net::Request& request) {
  constexpr std::string_view kPrefix = "bearer.";
  for (const std::string_view item : net::offeredSubprotocols(request)) {
    if (item.starts_with(kPrefix)) return std::string(item.substr(kPrefix.size()));
  }
  return std::nullopt;
}

Authenticator::Authenticator(AuthConfig config) : config_(std::move(config)) {}

std::optional<Principal> Authenticator::lookup(std::string_view token) const {
  for (const TokenConfig& t : config_.tokens) {
    if (sameToken(t.token, token)) return Principal{t.role, t.robot_id};
  }
  return std::nullopt;
}

AuthResult Authenticator::authenticate(const net::Request& request, const net::Peer& peer) const {
  AuthResult result;
  if (loopbackOnly()) {
    if (peer.loopback) {
      result.principal = Principal{Role::kAdmin, {}};
    } else {
      result.status = 403;
      result.code = "loopback_only";
      result.message = "no tokens are configured, so only loopback clients are served";
    }
    return result;
  }
  std::optional<std::string> token;
  const auto authorization = request.find(http::field::authorization);
  if (authorization != request.end()) {
    const std::string_view value = trim(std::string_view(authorization->value().data(), authorization->value().size()));
    // Auth schemes are case-insensitive (RFC 7235 §2.1): "bearer" and "BEARER" are "Bearer".
    constexpr std::string_view kBearer = "bearer ";
    const bool bearer = value.size() > kBearer.size() &&
                        boost::beast::iequals(boost::beast::string_view(value.data(), kBearer.size()),
                                              boost::beast::string_view(kBearer.data(), kBearer.size()));
    if (!bearer) {
      result.code = "unauthenticated";
      result.message = "Authorization must be 'Bearer <token>'";
      return result;
    }
    token = std::string(trim(value.substr(kBearer.size())));
  } else {
    token = tokenFromSubprotocols(request);
  }
  if (!token) {
    result.code = "unauthenticated";
    result.message = "a bearer token is required";
    return result;
  }
  result.principal = lookup(*token);
  if (!result.principal) {
    result.code = "unauthenticated";
    result.message = "the token is not valid";
  }
  return result;
}

bool Authenticator::originAllowed(const net::Request& request) const {
  const auto origin = request.find(http::field::origin);
  if (origin == request.end()) return true;
  const std::string_view value(origin->value().data(), origin->value().size());
  const auto host = request.find(http::field::host);
  if (host != request.end()) {
    const std::string_view host_value(host->value().data(), host->value().size());
    for (const std::string_view scheme : {"http://", "https://"}) {
      if (value.size() == scheme.size() + host_value.size() && value.substr(0, scheme.size()) == scheme &&
          value.substr(scheme.size()) == host_value) {
        return true;
      }
    }
  }
  return std::find(config_.allowed_origins.begin(), config_.allowed_origins.end(), value) !=
         config_.allowed_origins.end();
}

}  // namespace rmap::app
