#include "net/ws_session.h"

#include <boost/asio/buffer.hpp>
#include <boost/asio/dispatch.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core/bind_handler.hpp>
#include <boost/beast/core/buffers_to_string.hpp>
#include <boost/beast/core/flat_buffer.hpp>
#include <boost/beast/core/stream_traits.hpp>
#include <boost/beast/websocket/ssl.hpp>
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

/// A read buffer grown past this by a large message is given back to the
/// allocator instead of being kept for the connection's lifetime.
constexpr size_t kKeptReadBufferBytes = 64u << 10;

template <class Stream>
class WsSession final : public Session, public WsDriver, public std::enable_shared_from_this<WsSession<Stream>> {
  using std::enable_shared_from_this<WsSession>::shared_from_this;
  using std::enable_shared_from_this<WsSession>::weak_from_this;

 public:
  WsSession(Stream stream, ConnectionCount count, Peer peer, std::shared_ptr<ServerState> state, WsAccept& accept)
      : state_(std::move(state)),
        count_(std::move(count)),
        ws_(std::move(stream)),
        peer_(std::move(peer)),
        handler_(std::move(accept.handler)),
        max_send_queue_bytes_(accept.max_send_queue_bytes),
        timeouts_(websocket::stream_base::timeout::suggested(beast::role_type::server)),
        pause_timer_(ws_.get_executor()),
        close_timer_(ws_.get_executor()) {
    // Server-side pings at half the idle timeout keep quiet but live peers
    // open; a peer silent for the whole timeout is dropped.
    timeouts_.idle_timeout = state_->options.idle_timeout;
    ws_.set_option(timeouts_);
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
    if (accept.socket_send_buffer_bytes != 0) {
      beast::error_code ignored;  // the system's buffer is still a working one
      beast::get_lowest_layer(ws_).set_option(
          asio::socket_base::send_buffer_size(static_cast<int>(accept.socket_send_buffer_bytes)), ignored);
    }
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
    asio::post(ws_.get_executor(), [self = shared_from_this()] { self->goAway(); });
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
    while (!finished_ && !closing_ && !channel_->paused()) {
      if (!pending_) {
        if (!reading_) {
          reading_ = true;
          unwatch();
          ws_.async_read(buffer_, beast::bind_front_handler(&WsSession::onRead, shared_from_this()));
        }
        return;
      }
      WsChannel::Frame message = std::move(*pending_);
      pending_.reset();
      callHandler([&] { handler_->onMessage(std::move(message.data), message.binary); });
    }
    if (!finished_ && !closing_ && !reading_) watch();
  }

  void onRead(beast::error_code ec, size_t /*bytes*/) {
    reading_ = false;
    // Errors include the peer's close, the idle timeout and message_too_big;
    // Beast has already answered the protocol side of each.
    if (ec) return finish();
    pending_ = WsChannel::Frame{beast::buffers_to_string(buffer_.data()), ws_.got_binary()};
    buffer_.consume(buffer_.size());
    if (buffer_.capacity() > kKeptReadBufferBytes) buffer_.shrink_to_fit();
    pump();
  }

  // Paused reading. Beast sees pongs (and any frame) only while a read is
  // pending, so its idle timeout would drop a healthy peer the application
  // paused. It is suspended meanwhile, and this watch keeps its rule: ping
  // every half idle timeout, and close when nothing arrived for a whole one.
  // What arrived is what waits unread in the socket; a peer with bytes
  // waiting is judged by Beast again once reading resumes, and one whose
  // host vanished fails the pings' writes.

  void watch() {
    if (watching_) return;
    watching_ = true;
    silent_ticks_ = 0;
    auto paused = timeouts_;
    paused.idle_timeout = websocket::stream_base::none();
    ws_.set_option(paused);
    armWatch();
  }

  void unwatch() {
    if (!watching_) return;
    watching_ = false;
    pause_timer_.cancel();
    ws_.set_option(timeouts_);  // the read about to start restarts Beast's timer
  }

  void armWatch() {
    pause_timer_.expires_after(timeouts_.idle_timeout / 2);
    pause_timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (!ec) self->onWatchTick();
    });
  }

  void onWatchTick() {
    if (finished_ || closing_ || !watching_) return;
    beast::error_code ec;
    const size_t waiting = beast::get_lowest_layer(ws_).available(ec);
    if (ec) return finish();
    silent_ticks_ = waiting > 0 ? 0 : silent_ticks_ + 1;
    if (silent_ticks_ >= 2) return finish();  // as Beast's timeout: the socket closes, no close frame
    if (!pinging_) {
      pinging_ = true;
      ws_.async_ping({}, [self = shared_from_this()](beast::error_code ping_ec) {
        self->pinging_ = false;
        if (ping_ec && !self->closing_) self->finish();  // a close aborts the ping: not an error then
      });
    }
    armWatch();
  }

  /// Starts the next write unless the queue is empty; one at a time.
  void writeNext() {
    if (finished_ || closing_) return;
    WsChannel::CloseRequest close;
    switch (channel_->next(writing_frame_, close)) {
      case WsChannel::Next::kFrame:
        writing_ = true;
        ws_.binary(writing_frame_.binary);
        ws_.async_write(asio::buffer(writing_frame_.data),
                        beast::bind_front_handler(&WsSession::onWrite, shared_from_this()));
        return;
      case WsChannel::Next::kClose:
        startClose(websocket::close_reason(static_cast<websocket::close_code>(close.code), close.reason));
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

  /// The close handshake; Beast lets it overlap a write still running, and
  /// reads the peer's frames up to its close frame itself. Nothing is
  /// written or delivered after it.
  void startClose(const websocket::close_reason& reason) {
    closing_ = true;
    ws_.async_close(reason, [self = shared_from_this()](beast::error_code) { self->finish(); });
  }

  /// Server::stop(): the queued frames are dropped (a slow reader could hold
  /// them for long) and a close frame says why, unless a close handshake
  /// already runs; either way close_timeout bounds it.
  void goAway() {
    if (finished_) return;
    if (!opened_) return finish();  // mid-handshake: nothing to close politely
    channel_->detach();
    close_timer_.expires_after(state_->options.close_timeout);
    close_timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (!ec) self->finish();
    });
    if (!closing_) startClose(websocket::close_reason(websocket::close_code::going_away, "server stopping"));
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
    pause_timer_.cancel();
    close_timer_.cancel();
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).close(ignored);
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
  websocket::stream<Stream> ws_;
  const Peer peer_;
  std::shared_ptr<WsHandler> handler_;
  const size_t max_send_queue_bytes_;
  websocket::stream_base::timeout timeouts_;  ///< while reading is not paused
  asio::steady_timer pause_timer_;  ///< the watch while paused (see watch())
  asio::steady_timer close_timer_;  ///< bounds the close handshake of goAway()
  Request upgrade_;  ///< kept until the handshake completes
  beast::flat_buffer buffer_;
  std::shared_ptr<WsChannel> channel_;
  std::optional<WsChannel::Frame> pending_;  ///< read, not delivered: paused meanwhile
  WsChannel::Frame writing_frame_;
  bool reading_ = false;
  bool writing_ = false;
  bool opened_ = false;
  bool closing_ = false;  ///< async_close started
  bool finished_ = false;
  bool watching_ = false;  ///< paused with no read pending: Beast's idle timeout suspended
  bool pinging_ = false;  ///< a ping of the watch is being written
  int silent_ticks_ = 0;  ///< watch ticks in a row with nothing waiting in the socket
  std::optional<ServerState::Handle> handle_;
};

template <class Stream>
void startSession(Stream stream, ConnectionCount count, Peer peer, std::shared_ptr<ServerState> state,
                  WsAccept accept, Request upgrade) {
  std::make_shared<WsSession<Stream>>(std::move(stream), std::move(count), std::move(peer), std::move(state), accept)
      ->start(std::move(upgrade));
}

}  // namespace

void startWebSocketSession(PlainStream stream, ConnectionCount count, Peer peer, std::shared_ptr<ServerState> state,
                           WsAccept accept, Request upgrade) {
  startSession(std::move(stream), std::move(count), std::move(peer), std::move(state), std::move(accept),
               std::move(upgrade));
}

void startWebSocketSession(TlsStream stream, ConnectionCount count, Peer peer, std::shared_ptr<ServerState> state,
                           WsAccept accept, Request upgrade) {
  startSession(std::move(stream), std::move(count), std::move(peer), std::move(state), std::move(accept),
               std::move(upgrade));
}

}  // namespace rmap::net
