#include "net/ws_session.h"

#include <boost/asio/buffer.hpp>
#include <boost/asio/dispatch.hpp>
#include <boost/asio/post.hpp>
#include <boost/beast/core/bind_handler.hpp>
#include <boost/beast/core/buffers_to_string.hpp>
#include <boost/beast/core/flat_buffer.hpp>
#include <boost/beast/websocket/stream.hpp>
#include <optional>

#include "net/ws_channel.h"

namespace rmap::net {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;

/// Close code when a handler throws (RFC 6455 §7.4.1, internal error).
constexpr uint16_t kInternalError = 1011;

class WsSession final : public Session, public WsDriver, public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(asio::ip::tcp::socket socket, ConnectionCount count, Peer peer, std::shared_ptr<ServerState> state,
            WsAccept& accept)
      : state_(std::move(state)),
        count_(std::move(count)),
        ws_(std::move(socket)),
        peer_(std::move(peer)),
        handler_(std::move(accept.handler)),
        max_send_queue_bytes_(accept.max_send_queue_bytes) {
    // Server-side pings at half the idle timeout keep quiet but live peers
    // open; a peer silent for the whole timeout is dropped.
    auto timeouts = websocket::stream_base::timeout::suggested(beast::role_type::server);
    timeouts.idle_timeout = state_->options.idle_timeout;
    ws_.set_option(timeouts);
    ws_.set_option(websocket::stream_base::decorator(
        [subprotocol = std::move(accept.subprotocol)](websocket::response_type& response) {
          response.set(http::field::server, "rmapd");
          if (!subprotocol.empty()) response.set(http::field::sec_websocket_protocol, subprotocol);
        }));
    // Beast answers a larger message with close code 1009 (too big) and then
    // fails the read with error::message_too_big.
    ws_.read_message_max(accept.max_frame_bytes);
    // Messages go out as single frames; fragmenting buys nothing without
    // compression or interleaving.
    ws_.auto_fragment(false);
  }

  ~WsSession() override {
    if (handle_) state_->withdraw(*handle_);
  }

  void start(Request upgrade) {
    handle_ = state_->enroll(weak_from_this());
    if (!handle_) return;  // stopping: the socket closes with this session
    upgrade_ = std::move(upgrade);
    asio::dispatch(ws_.get_executor(), [self = shared_from_this()] {
      self->ws_.async_accept(self->upgrade_, beast::bind_front_handler(&WsSession::onAccept, self));
    });
  }

  void shutdown() override {
    asio::post(ws_.get_executor(), [self = shared_from_this()] { self->finish(); });
  }

  void flushQueue() override {
    if (!writing_) writeNext();
  }

  void resumeReading() override { pump(); }

 private:
  void onAccept(beast::error_code ec) {
    upgrade_ = Request{};
    if (ec || finished_) return finish();
    opened_ = true;
    ++state_->web_sockets;
    channel_ = std::make_shared<WsChannel>(peer_, max_send_queue_bytes_, shared_from_this(), ws_.get_executor());
    callHandler([this] { handler_->onOpen(channel_); });
    pump();
  }

  /// Delivers the message read while paused, if any, then keeps one read
  /// outstanding unless paused (so a paused client fills its TCP window).
  void pump() {
    while (!finished_ && !channel_->paused()) {
      if (!pending_) {
        if (!reading_) {
          reading_ = true;
          ws_.async_read(buffer_, beast::bind_front_handler(&WsSession::onRead, shared_from_this()));
        }
        return;
      }
      WsChannel::Frame message = std::move(*pending_);
      pending_.reset();
      callHandler([&] { handler_->onMessage(std::move(message.data), message.binary); });
    }
  }

  void onRead(beast::error_code ec, size_t /*bytes*/) {
    reading_ = false;
    // Errors include the peer's close, the idle timeout and message_too_big;
    // Beast has already answered the protocol side of each.
    if (ec) return finish();
    pending_ = WsChannel::Frame{beast::buffers_to_string(buffer_.data()), ws_.got_binary()};
    buffer_.consume(buffer_.size());
    pump();
  }

  /// Starts the next write unless the queue is empty; one at a time.
  void writeNext() {
    if (finished_) return;
    WsChannel::CloseRequest close;
    switch (channel_->next(writing_frame_, close)) {
      case WsChannel::Next::kFrame:
        writing_ = true;
        ws_.binary(writing_frame_.binary);
        ws_.async_write(asio::buffer(writing_frame_.data),
                        beast::bind_front_handler(&WsSession::onWrite, shared_from_this()));
        return;
      case WsChannel::Next::kClose:
        writing_ = true;
        ws_.async_close(websocket::close_reason(static_cast<websocket::close_code>(close.code), close.reason),
                        [self = shared_from_this()](beast::error_code) { self->finish(); });
        return;
      case WsChannel::Next::kIdle:
        return;
    }
  }

  void onWrite(beast::error_code ec, size_t /*bytes*/) {
    writing_ = false;
    if (ec) return finish();
    channel_->written(writing_frame_.data.size());
    writeNext();
  }

  /// Runs a handler callback; a throwing handler gets its connection closed.
  template <class Call>
  void callHandler(Call&& call) {
    try {
      call();
    } catch (...) {
      channel_->close(kInternalError, "internal error");
    }
  }

  /// Ends the connection once: sends fail from now on, the socket closes
  /// (aborting pending operations) and an opened handler gets onClose.
  void finish() {
    if (finished_) return;
    finished_ = true;
    if (channel_) channel_->detach();
    beast::error_code ignored;
    ws_.next_layer().close(ignored);
    if (!opened_) return;
    --state_->web_sockets;
    try {
      handler_->onClose();
    } catch (...) {
      // Nothing is left to report it to.
    }
    handler_.reset();
  }

  std::shared_ptr<ServerState> state_;
  ConnectionCount count_;
  websocket::stream<asio::ip::tcp::socket> ws_;
  const Peer peer_;
  std::shared_ptr<WsHandler> handler_;
  const size_t max_send_queue_bytes_;
  Request upgrade_;  ///< kept until the handshake completes
  beast::flat_buffer buffer_;
  std::shared_ptr<WsChannel> channel_;
  std::optional<WsChannel::Frame> pending_;  ///< read, not delivered: paused meanwhile
  WsChannel::Frame writing_frame_;
  bool reading_ = false;
  bool writing_ = false;
  bool opened_ = false;
  bool finished_ = false;
  std::optional<ServerState::Handle> handle_;
};

}  // namespace

void startWebSocketSession(asio::ip::tcp::socket socket, ConnectionCount count, Peer peer,
                           std::shared_ptr<ServerState> state, WsAccept accept, Request upgrade) {
  std::make_shared<WsSession>(std::move(socket), std::move(count), std::move(peer), std::move(state), accept)
      ->start(std::move(upgrade));
}

}  // namespace rmap::net
