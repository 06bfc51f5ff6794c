#include "net/http_session.h"

#include <boost/asio/dispatch.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/write.hpp>
#include <boost/beast/core/bind_handler.hpp>
#include <boost/beast/core/flat_buffer.hpp>
#include <boost/beast/core/stream_traits.hpp>
#include <boost/beast/http/parser.hpp>
#include <boost/beast/http/read.hpp>
#include <boost/beast/http/write.hpp>
#include <boost/beast/websocket/rfc6455.hpp>
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

#include "net/header_checks.h"
#include "net/json_error.h"
#include "net/peer.h"
#include "net/ws_handshake.h"
#include "net/ws_session.h"

namespace rmap::net {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;

/// Whether the parser rejected the bytes, as opposed to the socket failing.
bool isParseError(const beast::error_code& ec) {
  return ec.category() == http::make_error_code(http::error::bad_method).category();
}

/// Makes `response` answer a request of `version`: keep-alive only when both
/// sides want it, a Server header, a Content-Length unless the service chose
/// the framing itself (HEAD answers carry the length of the body they omit).
void finalize(Response& response, unsigned version, bool request_keep_alive) {
  response.version(version);
  response.keep_alive(request_keep_alive && response.keep_alive());
  if (response.find(http::field::server) == response.end()) response.set(http::field::server, "rmapd");
  if (!response.has_content_length() && !response.chunked()) response.prepare_payload();
}

/// The interim answer a client sending Expect: 100-continue waits for
/// before it sends the body.
constexpr std::string_view kContinue = "HTTP/1.1 100 Continue\r\n\r\n";

using Clock = std::chrono::steady_clock;

/// How long a connection answered with an error and closed keeps draining
/// what the client still sends (see HttpSession::linger).
constexpr std::chrono::seconds kLingerTime{2};
constexpr size_t kDrainChunk = 64u << 10;

template <class Stream>
class HttpSession final : public Session, public std::enable_shared_from_this<HttpSession<Stream>> {
  using std::enable_shared_from_this<HttpSession>::shared_from_this;
  using std::enable_shared_from_this<HttpSession>::weak_from_this;

 public:
  HttpSession(Stream stream, std::shared_ptr<ServerState> state)
      : state_(std::move(state)),
        count_(state_->connections),
        stream_(std::move(stream)),
        idle_timer_(stream_.get_executor()) {
    beast::error_code ec;
    const auto remote = socket().remote_endpoint(ec);
    if (!ec) peer_ = peerFromEndpoint(remote);
  }

  ~HttpSession() override {
    if (handle_) state_->withdraw(*handle_);
  }

  void start() {
    handle_ = state_->enroll(weak_from_this());
    if (!handle_) return;  // stopping: the socket closes with this session
    asio::dispatch(stream_.get_executor(), [self = shared_from_this()] { self->begin(); });
  }

  void shutdown() override {
    asio::post(stream_.get_executor(), [self = shared_from_this()] { self->closeSocket(); });
  }

 private:
  asio::ip::tcp::socket& socket() { return beast::get_lowest_layer(stream_); }

  /// The TLS handshake, like a request, must complete within the idle
  /// timeout; a failed one (a plain-HTTP client, a client that does not
  /// trust the certificate) closes the connection without an answer.
  void begin() {
    if constexpr (kIsTls<Stream>) {
      deadline_ = Clock::now() + state_->options.idle_timeout;
      stream_.async_handshake(asio::ssl::stream_base::server, [self = shared_from_this()](beast::error_code ec) {
        if (ec) return self->closeSocket();
        self->readRequest();
      });
    } else {
      readRequest();
    }
    armIdleTimer(deadline_);
  }

  // The idle timeout: each read or write sets the deadline it must meet, and
  // one timer checks the deadline when it fires. Re-arming a timer per
  // operation (as beast::tcp_stream does) costs a good share of a small
  // request.

  /// The timer holds the session weakly: it must not keep a finished one.
  void armIdleTimer(Clock::time_point deadline) {
    idle_timer_.expires_at(deadline);
    idle_timer_.async_wait([weak = weak_from_this()](beast::error_code ec) {
      if (auto self = weak.lock(); self && !ec) self->onIdleTimer();
    });
  }

  void onIdleTimer() {
    if (Clock::now() >= deadline_) return closeSocket();  // aborts the stalled operation
    armIdleTimer(deadline_);
  }

  /// Reads the header first: the request may have to be refused (or, with
  /// Expect: 100-continue, invited) before its body is read.
  void readRequest() {
    const ServerOptions& options = state_->options;
    parser_.emplace();
    parser_->header_limit(
        static_cast<std::uint32_t>(std::min<size_t>(options.max_header_bytes, std::numeric_limits<std::uint32_t>::max())));
    // A declared Content-Length over this fails the header read (413) before
    // any of the body is read.
    parser_->body_limit(options.max_body_bytes);
    deadline_ = Clock::now() + options.idle_timeout;
    http::async_read_header(stream_, buffer_, *parser_,
                            beast::bind_front_handler(&HttpSession::onHeader, shared_from_this()));
  }

  void onHeader(beast::error_code ec, size_t /*bytes*/) {
    if (ec) return failRead(ec);
    const Request& request = parser_->get();
    if (auto error = headerError(request, parser_->chunked())) return closeWith(std::move(*error));
    if (parser_->is_done()) return handleRequest();
    // headerError() let through no Expect but 100-continue.
    if (request.version() < 11 || request.find(http::field::expect) == request.end()) return readBody();
    asio::async_write(stream_, asio::buffer(kContinue.data(), kContinue.size()),
                      [self = shared_from_this()](beast::error_code write_ec, size_t) {
                        if (write_ec) return self->closeSocket();
                        self->readBody();
                      });
  }

  /// Within the deadline readRequest() set: the whole request must arrive in
  /// one idle timeout.
  void readBody() {
    http::async_read(stream_, buffer_, *parser_, beast::bind_front_handler(&HttpSession::onBody, shared_from_this()));
  }

  void onBody(beast::error_code ec, size_t /*bytes*/) {
    if (ec) return failRead(ec);
    handleRequest();
  }

  void failRead(const beast::error_code& ec) {
    const unsigned version = parser_->get().version();
    if (ec == http::error::body_limit) {
      return closeWith(jsonError(http::status::payload_too_large, "payload_too_large",
                                 "request body exceeds " + std::to_string(state_->options.max_body_bytes) + " bytes",
                                 version));
    }
    if (ec == http::error::header_limit) {
      return closeWith(jsonError(http::status::request_header_fields_too_large, "header_too_large",
                                 "request header exceeds " + std::to_string(state_->options.max_header_bytes) + " bytes",
                                 version));
    }
    // end_of_stream: the peer closed between requests; partial_message: it
    // left mid-request. Neither is waiting for an answer.
    if (isParseError(ec) && ec != http::error::end_of_stream && ec != http::error::partial_message) {
      return closeWith(jsonError(http::status::bad_request, "bad_request", ec.message(), version));
    }
    closeConnection();
  }

  void handleRequest() {
    Request& request = parser_->get();
    if (beast::websocket::is_upgrade(request)) return upgrade(parser_->release());
    Response response;
    try {
      response = state_->service.handleHttp(request, peer_);
    } catch (...) {
      // The message stays generic: exception texts are not for remote peers.
      response = internalError(request.version(), request.keep_alive());
    }
    finalize(response, request.version(), request.keep_alive());
    write(std::move(response));
  }

  void upgrade(Request request) {
    if (auto error = handshakeError(request)) return closeWith(std::move(*error));
    WsAccept accept;
    try {
      accept = state_->service.acceptWebSocket(request, peer_);
    } catch (...) {
      accept.refusal = internalError(request.version(), request.keep_alive());
    }
    if (!accept.handler) {
      finalize(accept.refusal, request.version(), request.keep_alive());
      return write(std::move(accept.refusal));
    }
    // RFC 6455 §4.2.2: the server selects one of the client's items, whole;
    // anything else would make the client fail the handshake.
    if (!offersSubprotocol(request, accept.subprotocol)) accept.subprotocol.clear();
    idle_timer_.cancel();  // the WebSocket stream runs its own timeouts
    startWebSocketSession(std::move(stream_), std::move(count_), peer_, state_, std::move(accept), std::move(request));
  }

  /// Sends an error response after which the request stream cannot be
  /// trusted to continue, then closes.
  void closeWith(Response response) {
    finalize(response, response.version(), false);
    lingering_ = true;
    write(std::move(response));
  }

  void write(Response response) {
    response_ = std::move(response);
    deadline_ = Clock::now() + state_->options.idle_timeout;
    http::async_write(stream_, response_, beast::bind_front_handler(&HttpSession::onWrite, shared_from_this()));
  }

  void onWrite(beast::error_code ec, size_t /*bytes*/) {
    if (ec) return closeSocket();
    if (lingering_) return linger();
    if (response_.need_eof()) return closeConnection();
    response_ = Response{};  // an idle keep-alive connection should not hold a large body
    readRequest();
  }

  /// After an error answer to a request not read to its end: FIN, then
  /// whatever the client still sends is dropped for at most kLingerTime.
  /// Closing with unread bytes would reset the connection, and a client
  /// still sending a body over the limit could lose the answer. Over TLS the
  /// drained bytes are records left undecrypted.
  void linger() {
    beast::error_code ignored;
    socket().shutdown(asio::ip::tcp::socket::shutdown_send, ignored);
    deadline_ = Clock::now() + kLingerTime;
    armIdleTimer(deadline_);
    drain();
  }

  void drain() {
    buffer_.clear();
    socket().async_read_some(buffer_.prepare(kDrainChunk), [self = shared_from_this()](beast::error_code ec, size_t) {
      if (ec) return self->closeSocket();  // the client closed too, or the deadline passed
      self->drain();
    });
  }

  /// Sends FIN; the socket closes when the session, now without pending
  /// operations, is destroyed. TLS sends no close_notify first: every
  /// response is framed by its Content-Length or chunks, so a client cannot
  /// take a truncated one for whole, and waiting for the peer's close_notify
  /// would hold the connection.
  void closeConnection() {
    beast::error_code ignored;
    socket().shutdown(asio::ip::tcp::socket::shutdown_send, ignored);
    idle_timer_.cancel();
  }

  void closeSocket() {
    beast::error_code ignored;
    socket().close(ignored);
    idle_timer_.cancel();
  }

  std::shared_ptr<ServerState> state_;
  ConnectionCount count_;
  Stream stream_;
  asio::steady_timer idle_timer_;
  Clock::time_point deadline_;  ///< when the current read or write must have completed
  Peer peer_;
  /// Reused across requests; holds the bytes of pipelined requests read ahead.
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  Response response_;  ///< being written
  bool lingering_ = false;  ///< closeWith() answered; the request stream is abandoned
  std::optional<ServerState::Handle> handle_;
};

}  // namespace

void startHttpSession(PlainStream stream, std::shared_ptr<ServerState> state) {
  std::make_shared<HttpSession<PlainStream>>(std::move(stream), std::move(state))->start();
}

void startHttpSession(TlsStream stream, std::shared_ptr<ServerState> state) {
  std::make_shared<HttpSession<TlsStream>>(std::move(stream), std::move(state))->start();
}

}  // namespace rmap::net
