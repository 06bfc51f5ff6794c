#pragma once
/// @file ws_session.h
/// Private to the net layer: one WebSocket connection after the Service
/// accepted the upgrade.

#include <memory>

#include "net/server_state.h"
#include "net/service.h"
#include "net/stream_types.h"

namespace rmap::net {

/// Completes the handshake for `upgrade` on `stream` (executor: a strand of
/// its own; a TLS stream has completed its TLS handshake), then runs the connection: complete messages go to
/// accept.handler in order on the strand, frames sent through the
/// WsConnection are written one at a time. When the handshake fails the
/// handler gets no call at all; once onOpen ran, onClose follows exactly once.
/// @param count the connection's unit of ServerState::connections, taken over
///        from the HTTP session
void startWebSocketSession(PlainStream stream, ConnectionCount count, Peer peer, std::shared_ptr<ServerState> state,
                           WsAccept accept, Request upgrade);
void startWebSocketSession(TlsStream stream, ConnectionCount count, Peer peer, std::shared_ptr<ServerState> state,
                           WsAccept accept, Request upgrade);

}  // namespace rmap::net
