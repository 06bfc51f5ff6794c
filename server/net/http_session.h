#pragma once
/// @file http_session.h
/// Private to the net layer: serving one accepted connection over HTTP/1.1
/// until it closes or upgrades to a WebSocket.

#include <boost/asio/ip/tcp.hpp>
#include <memory>

#include "net/server_state.h"

namespace rmap::net {

/// Serves `socket` (whose executor must be a strand of its own): requests are
/// read within the header/body limits of the options, answered in order
/// (keep-alive, pipelining), upgrades handed to the WebSocket session. The
/// session keeps itself alive through its pending operations.
void startHttpSession(boost::asio::ip::tcp::socket socket, std::shared_ptr<ServerState> state);

}  // namespace rmap::net
