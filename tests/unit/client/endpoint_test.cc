#include <gtest/gtest.h>

#include "client/robot_client.h"

namespace rmap::client {
namespace {

TEST(Endpoint, ParsesHostPortAndPath) {
  const Endpoint ws = Endpoint::parse("ws://127.0.0.1:8080");
  EXPECT_EQ(ws.host, "127.0.0.1");
  EXPECT_EQ(ws.port, "8080");
  EXPECT_EQ(ws.path, "/");

  const Endpoint with_path = Endpoint::parse("ws://robots.local:9000/v1/stream/robot");
  EXPECT_EQ(with_path.host, "robots.local");
  EXPECT_EQ(with_path.port, "9000");
  EXPECT_EQ(with_path.path, "/v1/stream/robot");

  const Endpoint http = Endpoint::parse("HTTP://Example.com:80/v1/maps?limit=3");
  EXPECT_EQ(http.host, "Example.com");
  EXPECT_EQ(http.path, "/v1/maps?limit=3");

  const Endpoint query_only = Endpoint::parse("http://h:1?x=1");
  EXPECT_EQ(query_only.path, "/?x=1");
}

TEST(Endpoint, DefaultsPortAndAcceptsIpv6Literals) {
  EXPECT_EQ(Endpoint::parse("http://example.com").port, "80");
  EXPECT_EQ(Endpoint::parse("ws://example.com/x").port, "80");

  const Endpoint v6 = Endpoint::parse("ws://[::1]:8080/a");
  EXPECT_EQ(v6.host, "::1");
  EXPECT_EQ(v6.port, "8080");
  EXPECT_EQ(v6.path, "/a");
  EXPECT_EQ(Endpoint::parse("http://[fe80::1]").port, "80");
}

TEST(Endpoint, RejectsEverythingElse) {
  for (const std::string url :
       {"", "localhost:8080", "ws:/h:1", "ftp://h:1", "ws://", "ws://:80", "ws://h:", "ws://h:0", "ws://h:65536",
        "ws://h:8a", "ws://h:-1", "ws://h:80#top", "ws://user@h:1", "ws://h:1/a b", "ws://[::1", "ws://[::1]x",
        "ws://[::1]:", "ws://[]:80"}) {
    EXPECT_THROW(Endpoint::parse(url), ClientError) << url;
  }
}

TEST(Endpoint, TlsSchemesSetTlsAndDefaultTo443) {
  const Endpoint wss = Endpoint::parse("WSS://robots.local/v1/stream/robot");
  EXPECT_TRUE(wss.tls);
  EXPECT_EQ(wss.host, "robots.local");
  EXPECT_EQ(wss.port, "443");
  EXPECT_EQ(wss.path, "/v1/stream/robot");
  const Endpoint https = Endpoint::parse("https://127.0.0.1:8443");
  EXPECT_TRUE(https.tls);
  EXPECT_EQ(https.port, "8443");
  EXPECT_FALSE(Endpoint::parse("ws://h:1").tls);
  EXPECT_FALSE(Endpoint::parse("http://h:1").tls);
}

}  // namespace
}  // namespace rmap::client
