#include "app/auth.h"

#include <gtest/gtest.h>

#include <boost/beast/http/field.hpp>

namespace rmap::app {
namespace {

namespace http = boost::beast::http;

const net::Peer kLoopback{"127.0.0.1", 50000, true};
const net::Peer kRemote{"192.0.2.7", 50000, false};

net::Request request(std::initializer_list<std::pair<http::field, std::string>> headers = {}) {
  net::Request r{http::verb::get, "/v1/maps", 11};
  for (const auto& [field, value] : headers) r.set(field, value);
  return r;
}

AuthConfig tokens() {
  AuthConfig config;
  config.tokens = {{"robot-token-1", Role::kRobot, "r1"}, {"viewer-token", Role::kViewer, ""}};
  return config;
}

TEST(AuthLoopbackOnly, LoopbackPeerIsAdmin) {
  const Authenticator auth(AuthConfig{});
  ASSERT_TRUE(auth.loopbackOnly());
  const AuthResult result = auth.authenticate(request(), kLoopback);
  ASSERT_TRUE(result.principal);
  EXPECT_EQ(result.principal->role, Role::kAdmin);
}

TEST(AuthLoopbackOnly, RemotePeerIsRefusedWith403) {
  const Authenticator auth(AuthConfig{});
  const AuthResult result = auth.authenticate(request({{http::field::authorization, "Bearer anything"}}), kRemote);
  EXPECT_FALSE(result.principal);
  EXPECT_EQ(result.status, 403);
  EXPECT_EQ(result.code, "loopback_only");
}

TEST(AuthTokens, ValidBearerGivesTheTokensPrincipal) {
  const Authenticator auth(tokens());
  EXPECT_FALSE(auth.loopbackOnly());
  const AuthResult robot = auth.authenticate(request({{http::field::authorization, "Bearer robot-token-1"}}), kRemote);
  ASSERT_TRUE(robot.principal);
  EXPECT_EQ(robot.principal->role, Role::kRobot);
  EXPECT_EQ(robot.principal->robot_id, "r1");
  const AuthResult viewer = auth.authenticate(request({{http::field::authorization, "Bearer viewer-token"}}), kRemote);
  ASSERT_TRUE(viewer.principal);
  EXPECT_EQ(viewer.principal->role, Role::kViewer);
}

TEST(AuthTokens, InvalidTokenIsRefusedWith401) {
  const Authenticator auth(tokens());
  for (const std::string token : {"viewer-tokem", "viewer-token2", "viewer", "VIEWER-TOKEN"}) {
    const AuthResult result = auth.authenticate(request({{http::field::authorization, "Bearer " + token}}), kRemote);
    EXPECT_FALSE(result.principal) << token;
    EXPECT_EQ(result.status, 401) << token;
    EXPECT_EQ(result.code, "unauthenticated") << token;
  }
}

TEST(AuthTokens, MissingTokenIsRefusedEvenOnLoopback) {
  const Authenticator auth(tokens());
  const AuthResult result = auth.authenticate(request(), kLoopback);
  EXPECT_FALSE(result.principal);
  EXPECT_EQ(result.status, 401);
  EXPECT_EQ(result.code, "unauthenticated");
}

TEST(AuthTokens, MalformedAuthorizationIsRefused) {
  const Authenticator auth(tokens());
  for (const std::string value : {"Basic x", "Bearer", "Bearer   ", "viewer-token", "Bearerviewer-token"}) {
    const AuthResult result = auth.authenticate(request({{http::field::authorization, value}}), kRemote);
    EXPECT_FALSE(result.principal) << value;
    EXPECT_EQ(result.status, 401) << value;
  }
}

TEST(AuthTokens, BearerTokenIsTrimmed) {
  const Authenticator auth(tokens());
  EXPECT_TRUE(auth.authenticate(request({{http::field::authorization, "Bearer   viewer-token "}}), kRemote).principal);
}

TEST(AuthTokens, BearerSchemeIsCaseInsensitive) {
  const Authenticator auth(tokens());
  for (const std::string scheme : {"bearer", "BEARER", "bEaReR"}) {
    EXPECT_TRUE(auth.authenticate(request({{http::field::authorization, scheme + " viewer-token"}}), kRemote).principal)
        << scheme;
  }
  // The token itself stays case-sensitive.
  EXPECT_FALSE(auth.authenticate(request({{http::field::authorization, "bearer VIEWER-TOKEN"}}), kRemote).principal);
}

TEST(AuthTokens, TokenInWebSocketSubprotocol) {
  const Authenticator auth(tokens());
  const AuthResult result =
      auth.authenticate(request({{http::field::sec_websocket_protocol, "rmap.v1, bearer.robot-token-1"}}), kRemote);
  ASSERT_TRUE(result.principal);
  EXPECT_EQ(result.principal->robot_id, "r1");
}

TEST(AuthTokens, WrongSubprotocolTokenIsRefused) {
  const Authenticator auth(tokens());
  for (const std::string offer : {"rmap.v1, bearer.wrong-token", "rmap.v1", "rmap.v1, bearer."}) {
    const AuthResult result = auth.authenticate(request({{http::field::sec_websocket_protocol, offer}}), kRemote);
    EXPECT_FALSE(result.principal) << offer;
    EXPECT_EQ(result.status, 401) << offer;
  }
}

TEST(AuthTokens, AuthorizationHeaderTakesPrecedenceOverSubprotocol) {
  const Authenticator auth(tokens());
  const AuthResult result = auth.authenticate(request({{http::field::authorization, "Bearer wrong-token"},
                                                       {http::field::sec_websocket_protocol, "bearer.viewer-token"}}),
                                              kRemote);
  EXPECT_FALSE(result.principal);
}

/// The token found in a request offering `protocols`.
std::optional<std::string> offered(const std::string& protocols) {
  return tokenFromSubprotocols(request({{http::field::sec_websocket_protocol, protocols}}));
}

TEST(TokenFromSubprotocols, FindsTheBearerItem) {
  EXPECT_EQ(offered("rmap.v1, bearer.abc"), "abc");
  EXPECT_EQ(offered("bearer.abc,rmap.v1"), "abc");
  EXPECT_EQ(offered("  bearer.abc  "), "abc");
  EXPECT_EQ(offered(",,\tbearer.a.b.c\t,"), "a.b.c");
  EXPECT_EQ(offered("bearer.first, bearer.second"), "first");
}

TEST(TokenFromSubprotocols, NoBearerItemGivesNothing) {
  EXPECT_FALSE(offered(""));
  EXPECT_FALSE(offered("rmap.v1"));
  EXPECT_FALSE(offered("rmap.v1, Bearer.abc"));
  EXPECT_FALSE(offered("rmap.v1, xbearer.abc"));
  EXPECT_FALSE(offered("bearer"));
}

TEST(OriginAllowed, NoOriginIsAllowed) {
  const Authenticator auth(AuthConfig{});
  EXPECT_TRUE(auth.originAllowed(request({{http::field::host, "map.example:8080"}})));
}

TEST(OriginAllowed, SameHostIsAllowedOverHttpAndHttps) {
  const Authenticator auth(AuthConfig{});
  EXPECT_TRUE(auth.originAllowed(
      request({{http::field::host, "map.example:8080"}, {http::field::origin, "http://map.example:8080"}})));
  EXPECT_TRUE(auth.originAllowed(
      request({{http::field::host, "map.example:8080"}, {http::field::origin, "https://map.example:8080"}})));
}

TEST(OriginAllowed, ForeignOriginIsRefused) {
  const Authenticator auth(AuthConfig{});
  for (const std::string origin : {"http://evil.example", "http://map.example:8081", "http://map.example:8080.evil",
                                   "ftp://map.example:8080", "null"}) {
    EXPECT_FALSE(
        auth.originAllowed(request({{http::field::host, "map.example:8080"}, {http::field::origin, origin}})))
        << origin;
  }
  EXPECT_FALSE(auth.originAllowed(request({{http::field::origin, "http://map.example:8080"}})));
}

TEST(OriginAllowed, ListedOriginIsAllowed) {
  AuthConfig config;
  config.allowed_origins = {"https://app.example"};
  const Authenticator auth(config);
  EXPECT_TRUE(auth.originAllowed(
      request({{http::field::host, "map.example:8080"}, {http::field::origin, "https://app.example"}})));
  EXPECT_FALSE(auth.originAllowed(
      request({{http::field::host, "map.example:8080"}, {http::field::origin, "http://app.example"}})));
}

}  // namespace
}  // namespace rmap::app
