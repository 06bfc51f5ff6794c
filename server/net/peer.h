#pragma once
/// @file peer.h
/// Private to the net layer: the Peer a connection's remote endpoint makes.

#include <boost/asio/ip/tcp.hpp>

#include "net/service.h"

namespace rmap::net {

/// IPv4-mapped IPv6 addresses (::ffff:a.b.c.d, seen on dual-stack listeners)
/// are reported, and judged for loopback, as the IPv4 address they carry.
Peer peerFromEndpoint(const boost::asio::ip::tcp::endpoint& endpoint);

}  // namespace rmap::net
