#include "net/ws_handshake.h"

#include <gtest/gtest.h>

#include <boost/beast/http/field.hpp>
#include <string>
#include <vector>

namespace rmap::net {
namespace {

namespace http = boost::beast::http;

Request withProtocols(const std::vector<std::string>& fields) {
  Request request{http::verb::get, "/ws", 11};
  for (const std::string& field : fields) request.insert(http::field::sec_websocket_protocol, field);
  return request;
}

Request upgrade(const std::string& key, const std::string& version) {
  Request request{http::verb::get, "/ws", 11};
  request.set(http::field::host, "x");
  request.set(http::field::connection, "Upgrade");
  request.set(http::field::upgrade, "websocket");
  if (!key.empty()) request.set(http::field::sec_websocket_key, key);
  if (!version.empty()) request.set(http::field::sec_websocket_version, version);
  return request;
}

TEST(WsHandshake, OfferedSubprotocolsAreTrimmedItemsOfEveryField) {
  const Request request = withProtocols({" rmap.v1 ,\tbearer.abc", ",, x.y ,", "last"});
  const std::vector<std::string_view> expected = {"rmap.v1", "bearer.abc", "x.y", "last"};
  EXPECT_EQ(offeredSubprotocols(request), expected);
  EXPECT_TRUE(offeredSubprotocols(withProtocols({})).empty());
  EXPECT_TRUE(offeredSubprotocols(withProtocols({" , "})).empty());
}

TEST(WsHandshake, SubprotocolsMatchWholeItemsOnly) {
  EXPECT_TRUE(offersSubprotocol(withProtocols({"rmap.v1, bearer.abc"}), "rmap.v1"));
  EXPECT_TRUE(offersSubprotocol(withProtocols({"bearer.abc", "rmap.v1"}), "rmap.v1"));
  for (const char* offer : {"rmap.v1x", "xrmap.v1", "bearer.rmap.v1", "rmap.v1.2", "RMAP.V1", "rmap. v1"}) {
    EXPECT_FALSE(offersSubprotocol(withProtocols({offer}), "rmap.v1")) << offer;
  }
  EXPECT_FALSE(offersSubprotocol(withProtocols({}), "rmap.v1"));
}

TEST(WsHandshake, WellFormedUpgradePasses) {
  EXPECT_FALSE(handshakeError(upgrade("dGhlIHNhbXBsZSBub25jZQ==", "13")));
}

TEST(WsHandshake, KeyMustBeSixteenBytesInBase64) {
  for (const char* key : {"", "dGhlIHNhbXBsZSBub25jZQ", "dGhlIHNhbXBsZSBub25jZQ=", "dGhlIHNhbXBsZSBub25jZQ==x",
                          "dGhlIHNhbXBsZSBub25j*Q==", "dGhlIHNhbXBsZSBub25jZQ=A"}) {
    const auto error = handshakeError(upgrade(key, "13"));
    ASSERT_TRUE(error) << key;
    EXPECT_EQ(error->result(), http::status::bad_request) << key;
  }
}

TEST(WsHandshake, OtherVersionsGet426Naming13) {
  for (const char* version : {"", "8", "13, 8", "14"}) {
    const auto error = handshakeError(upgrade("dGhlIHNhbXBsZSBub25jZQ==", version));
    ASSERT_TRUE(error) << version;
    EXPECT_EQ(error->result(), http::status::upgrade_required) << version;
    EXPECT_EQ((*error)[http::field::sec_websocket_version], "13");
  }
}

}  // namespace
}  // namespace rmap::net
