#pragma once
/// @file ws_handshake.h
/// The parts of a WebSocket opening handshake (RFC 6455 §4.2.1) the net layer
/// checks before the Service sees an upgrade request, and the subprotocol
/// offer, which the Service may also read (e.g. for a "bearer.<token>" item).

#include <optional>
#include <string_view>
#include <vector>

#include "net/service.h"

namespace rmap::net {

/// The items of every Sec-WebSocket-Protocol field of `request`, in order,
/// with surrounding spaces and tabs trimmed and empty items dropped. Views
/// into `request`.
std::vector<std::string_view> offeredSubprotocols(const Request& request);

/// Whether `name` is one of offeredSubprotocols(request), compared whole and
/// case-sensitively ("rmap.v1x" does not offer "rmap.v1").
bool offersSubprotocol(const Request& request, std::string_view name);

/// The JSON error answering an upgrade request that no WebSocket handshake
/// can complete: a Sec-WebSocket-Key that is not 16 bytes in base64 (400) or
/// a Sec-WebSocket-Version other than 13 (426, naming 13). Nullopt when the
/// request is well formed; `request` must pass websocket::is_upgrade.
std::optional<Response> handshakeError(const Request& request);

}  // namespace rmap::net
