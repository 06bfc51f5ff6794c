#pragma once
/// @file auth.h
/// Who may do what. Tokens come from the config; a request carries one as
/// `Authorization: Bearer <token>`, or on browser WebSockets as the
/// subprotocol `bearer.<token>` next to `rmap.v1`. With no tokens configured
/// the server is in loopback-only mode: loopback peers get admin rights and
/// everyone else is refused.

#include <optional>
#include <string>
#include <string_view>

#include "app/config.h"
#include "net/service.h"

namespace rmap::app {

struct Principal {
  Role role = Role::kViewer;
  std::string robot_id;  ///< robot role only
};

/// Outcome of authentication: a principal, or the HTTP status and message of the refusal.
struct AuthResult {
  std::optional<Principal> principal;
  int status = 401;
  std::string code;
  std::string message;
};

class Authenticator {
 public:
  explicit Authenticator(AuthConfig config);

  /// Authenticates a request from its Authorization header or, for WebSocket
  /// upgrades, its Sec-WebSocket-Protocol offer.
  AuthResult authenticate(const net::Request& request, const net::Peer& peer) const;

  /// Whether a browser Origin header may open a WebSocket: absent (not a
  /// browser), the server's own Host, or listed in allowed_origins.
  bool originAllowed(const net::Request& request) const;

  bool loopbackOnly() const { return config_.tokens.empty(); }

 private:
  std::optional<Principal> lookup(std::string_view token) const;
  AuthConfig config_;
};

/// The token offered as a Sec-WebSocket-Protocol item "bearer.<token>" (the
/// first such item of every field), if any.
std::optional<std::string> tokenFromSubprotocols(const net::Request& request);

}  // namespace rmap::app
