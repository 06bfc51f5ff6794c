#include "net/peer.h"

#include <gtest/gtest.h>

namespace rmap::net {
namespace {

Peer peerOf(const char* address, uint16_t port = 4242) {
  return peerFromEndpoint({boost::asio::ip::make_address(address), port});
}

TEST(Peer, Ipv4LoopbackIsTheWhole127Network) {
  EXPECT_TRUE(peerOf("127.0.0.1").loopback);
  EXPECT_TRUE(peerOf("127.255.3.4").loopback);
  EXPECT_FALSE(peerOf("128.0.0.1").loopback);
  EXPECT_FALSE(peerOf("10.0.0.1").loopback);
}

TEST(Peer, Ipv6Loopback) {
  EXPECT_TRUE(peerOf("::1").loopback);
  EXPECT_FALSE(peerOf("::2").loopback);
  EXPECT_FALSE(peerOf("2001:db8::1").loopback);
}

TEST(Peer, V4MappedAddressesAreReportedAsIpv4) {
  const Peer mapped_loopback = peerOf("::ffff:127.0.0.1");
  EXPECT_TRUE(mapped_loopback.loopback);
  EXPECT_EQ(mapped_loopback.address, "127.0.0.1");
  const Peer mapped_remote = peerOf("::ffff:192.0.2.7");
  EXPECT_FALSE(mapped_remote.loopback);
  EXPECT_EQ(mapped_remote.address, "192.0.2.7");
}

TEST(Peer, CarriesAddressAndPort) {
  const Peer peer = peerOf("192.0.2.1", 8080);
  EXPECT_EQ(peer.address, "192.0.2.1");
  EXPECT_EQ(peer.port, 8080);
}

}  // namespace
}  // namespace rmap::net
