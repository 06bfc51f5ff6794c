#pragma once
/// @file http_session.h
/// Private to the net layer: serving one accepted connection over HTTP/1.1
/// until it closes or upgrades to a WebSocket.

#include <memory>

#include "net/server_state.h"
#include "net/stream_types.h"

namespace rmap::net {

/// Serves `stream` (whose executor must be a strand of its own): a TLS
/// stream first completes its server handshake, then requests are read
/// within the header/body limits of the options, answered in order
/// (keep-alive, pipelining), upgrades handed to the WebSocket session. The
/// session keeps itself alive through its pending operations.
void startHttpSession(PlainStream stream, std::shared_ptr<ServerState> state);
void startHttpSession(TlsStream stream, std::shared_ptr<ServerState> state);

}  // namespace rmap::net
