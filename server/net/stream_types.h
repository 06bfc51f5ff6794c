#pragma once
/// @file stream_types.h
/// Private to the net layer: the two streams a connection runs on. The
/// sessions are templates over them, so plain and TLS connections share
/// every line of HTTP and WebSocket handling.

#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/ssl/stream.hpp>
#include <type_traits>

namespace rmap::net {

using PlainStream = boost::asio::ip::tcp::socket;
using TlsStream = boost::asio::ssl::stream<boost::asio::ip::tcp::socket>;

template <class Stream>
inline constexpr bool kIsTls = std::is_same_v<Stream, TlsStream>;

}  // namespace rmap::net
