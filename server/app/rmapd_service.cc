#include "app/rmapd_service.h"

#include "app/robot_session.h"
#include "app/viewer_hub.h"
#include "net/json_error.h"
#include "net/ws_handshake.h"

namespace rmap::app {

namespace http = boost::beast::http;

namespace {

constexpr std::string_view kSubprotocol = "rmap.v1";
/// A viewer's frames are small JSON notices (tiles come over HTTP): 64 KiB of socket
/// buffer carries megabytes per second even over Wi-Fi, and a stalled viewer's backlog
/// then grows in its send queue, bounded by limits.viewer_send_queue_bytes and skipped,
/// instead of in the kernel's autotuned buffer (megabytes per viewer).
constexpr size_t kViewerSocketSendBytes = 64u << 10;

net::WsAccept refuse(const net::Request& request, int status, const std::string& code, const std::string& message) {
  net::WsAccept accept;
  accept.refusal = net::jsonError(static_cast<http::status>(status), code, message, request.version(), false);
  return accept;
}

/// Echo "rmap.v1" when the client offered subprotocols (browsers require one of theirs back).
std::string chooseSubprotocol(const net::Request& request) {
  return net::offersSubprotocol(request, kSubprotocol) ? std::string(kSubprotocol) : std::string();
}

}  // namespace

RmapdService::RmapdService(MappingService& service)
    : service_(service), auth_(service.config().auth), api_(service, auth_) {}

net::Response RmapdService::handleHttp(net::Request& request, const net::Peer& peer) {
  return api_.handle(request, peer);
}

net::WsAccept RmapdService::acceptWebSocket(const net::Request& request, const net::Peer& peer) {
  Target target;
  try {
    target = Target::parse(std::string_view(request.target().data(), request.target().size()));
  } catch (const ApiError& e) {
    return refuse(request, e.status(), e.code(), e.what());
  }
  const std::vector<std::string>& s = target.segments;
  const bool robot_stream = s == std::vector<std::string>{"v1", "stream", "robot"};
  const bool viewer_stream = s == std::vector<std::string>{"v1", "stream", "viewer"};
  if (!robot_stream && !viewer_stream) return refuse(request, 404, "not_found", "no such stream");
  if (!auth_.originAllowed(request)) {
    return refuse(request, 403, "origin_not_allowed", "this Origin may not open streams on this server");
  }
  const AuthResult auth = auth_.authenticate(request, peer);
  if (!auth.principal) return refuse(request, auth.status, auth.code, auth.message);

  const LimitsConfig& limits = service_.config().limits;
  net::WsAccept accept;
  accept.subprotocol = chooseSubprotocol(request);
  accept.max_frame_bytes = limits.max_frame_bytes;
  if (robot_stream) {
    if (auth.principal->role == Role::kViewer) {
      return refuse(request, 403, "permission_denied", "a viewer token cannot stream robot data");
    }
    accept.handler = std::make_shared<RobotSession>(service_, *auth.principal);
    accept.max_send_queue_bytes = 4u << 20;
  } else {
    const std::string map = target.text("map");
    if (!map.empty() && !service_.findMap(map)) return refuse(request, 404, "map_not_found", "no map named '" + map + "'");
    accept.handler = std::make_shared<ViewerSession>(service_.viewers(), map);
    accept.max_send_queue_bytes = limits.viewer_send_queue_bytes;
    accept.socket_send_buffer_bytes = kViewerSocketSendBytes;
    accept.max_frame_bytes = 64u << 10;  // viewers only send small control frames
  }
  return accept;
}

}  // namespace rmap::app
