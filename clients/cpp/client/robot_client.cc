// RobotClient: the robot stream over Beast WebSocket, plain (ws://) or TLS (wss://).
//
// Every operation on the socket runs on one I/O thread (asynchronous Beast
// calls): a Beast stream must not be used by two threads at once, and its
// reads write on their own (pong and close replies), so a reader thread plus
// mutex-guarded writers from other threads would race; synchronous calls also
// cannot time out nor close the session while a read is pending. Callers talk
// to the I/O thread through posted handlers and wait on a condition variable
// with deadlines, so no call blocks longer than its timeout.

#include "client/robot_client.h"

#include <algorithm>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <deque>
#include <optional>
#include <thread>
#include <unordered_map>
#include <utility>

#include "client/tls_client.h"

namespace rmap::client {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using Clock = std::chrono::steady_clock;
using PlainWebSocket = websocket::stream<beast::tcp_stream>;
using TlsWebSocket = websocket::stream<TlsTcpStream>;

constexpr const char* kStreamPath = "/v1/stream/robot";

std::string describeClose(const websocket::close_reason& reason) {
  std::string text = "server closed the WebSocket (code " + std::to_string(reason.code);
  if (!reason.reason.empty()) text += ": " + std::string(reason.reason.data(), reason.reason.size());
  return text + ")";
}

}  // namespace

struct RobotClient::Impl {
  enum class State { idle, connecting, open, closing, closed };

  struct Frame {
    std::string bytes;
    bool binary = true;
  };

  explicit Impl(RobotClientOptions o)
      : options(std::move(o)), endpoint(Endpoint::parse(options.server_url)) {
    // "/" means "the server's robot stream"; any other path is kept (a proxy prefix).
    target = endpoint.path == "/" ? kStreamPath : endpoint.path;
    options.max_in_flight = std::max<size_t>(1, options.max_in_flight);
    if (endpoint.tls) tls = makeClientTlsContext(options.ca_file);
  }

  RobotClientOptions options;
  Endpoint endpoint;
  std::string target;
  std::shared_ptr<asio::ssl::context> tls;  ///< wss:// only
  AckCallback ack_callback;
  PoseCallback pose_callback;
  ErrorCallback error_callback;

  // ---- I/O thread only (set up by connect() before the thread starts) ----
  asio::io_context ioc;
  std::optional<tcp::resolver> resolver;
  // One of them is set per session, as the scheme says.
  std::optional<PlainWebSocket> ws;
  std::optional<TlsWebSocket> wss;
  beast::flat_buffer read_buffer;
  websocket::response_type upgrade_response;
  std::deque<Frame> write_queue;
  bool writing = false;
  bool close_requested = false;
  bool aborted = false;
  std::thread io_thread;

  /// Serialises send()/sendRaw()/connect() so frames leave in sequence order.
  std::mutex send_mutex;

  // ---- shared, guarded by `mutex` ----
  mutable std::mutex mutex;
  std::condition_variable cv;
  State state = State::idle;
  bool io_running = false;
  std::string stage;    ///< what connect() waits for, for its timeout message
  std::string failure;  ///< why the session ended
  std::optional<rmap::v1::Welcome> welcome;
  std::optional<rmap::v1::Error> last_error;
  uint64_t next_seq = 1;
  uint64_t last_sent = 0;
  uint64_t last_acked = 0;
  uint64_t acked = 0;
  std::unordered_map<uint64_t, Clock::time_point> in_flight;  ///< seq → send time

  // ---------------------------------------------------------------- I/O side

  /// Runs `operation` on the session's WebSocket stream.
  template <class Operation>
  void withWebSocket(Operation&& operation) {
    if (wss) {
      operation(*wss);
    } else {
      operation(*ws);
    }
  }

  beast::tcp_stream* transport() {
    if (wss) return &beast::get_lowest_layer(*wss);
    return ws ? &beast::get_lowest_layer(*ws) : nullptr;
  }

  void setStage(std::string what) {
    std::lock_guard lock(mutex);
    stage = std::move(what);
  }

  /// Ends the session with a reason (the first reason wins).
  void fail(const std::string& why) {
    {
      std::lock_guard lock(mutex);
      if (state != State::closed) {
        failure = why;
        state = State::closed;
      }
    }
    cv.notify_all();
    abort();
  }

  /// Cancels every pending operation and closes the socket.
  void abort() {
    aborted = true;
    if (resolver) resolver->cancel();
    if (beast::tcp_stream* stream = transport()) stream->close();
  }

  void startConnect() {
    setStage("resolving " + endpoint.host);
    resolver->async_resolve(endpoint.host, endpoint.port,
                            [this](beast::error_code ec, const tcp::resolver::results_type& results) {
                              if (ec) return fail("resolving " + endpoint.host + ": " + ec.message());
                              if (aborted) return;
                              setStage("connecting");
                              transport()->async_connect(
                                  results, [this](beast::error_code ec, const tcp::endpoint&) { onConnected(ec); });
                            });
  }

  void onConnected(beast::error_code ec) {
    if (ec) return fail("TCP connect: " + ec.message());
    if (aborted) return;
    transport()->socket().set_option(tcp::no_delay(true), ec);  // acks are latency-bound
    if (!wss) return upgrade();
    try {
      prepareTlsStream(wss->next_layer(), endpoint.host);
    } catch (const ClientError& e) {
      return fail(e.what());
    }
    setStage("TLS handshake");
    wss->next_layer().async_handshake(asio::ssl::stream_base::client, [this](beast::error_code ec) {
      if (ec) return fail("TLS handshake: " + ec.message());
      if (!aborted) upgrade();
    });
  }

  void upgrade() {
    setStage("WebSocket upgrade");
    const std::string host = endpoint.host.find(':') != std::string::npos ? "[" + endpoint.host + "]" : endpoint.host;
    withWebSocket([&](auto& stream) {
      stream.set_option(websocket::stream_base::decorator([token = options.token](websocket::request_type& request) {
        request.set(beast::http::field::user_agent, "rmap-client");
        if (!token.empty()) request.set(beast::http::field::authorization, "Bearer " + token);
      }));
      // No Beast timeouts: its timer would outlive abort() and keep the I/O
      // thread alive; connect() and close() enforce their own deadlines.
      stream.auto_fragment(false);
      stream.async_handshake(upgrade_response, host + ":" + endpoint.port, target,
                             [this](beast::error_code ec) { onHandshake(ec); });
    });
  }

  void onHandshake(beast::error_code ec) {
    if (ec == websocket::error::upgrade_declined) {
      return fail("upgrade refused: HTTP " + std::to_string(upgrade_response.result_int()) + " " +
                  std::string(upgrade_response.reason()) + ": " + upgrade_response.body());
    }
    if (ec) return fail("WebSocket upgrade: " + ec.message());
    if (aborted) return;
    setStage("Welcome");
    rmap::v1::RobotMessage hello;
    *hello.mutable_hello() = options.hello;
    enqueue({hello.SerializeAsString(), true});
    startRead();
  }

  void startRead() {
    withWebSocket([&](auto& stream) {
      stream.async_read(read_buffer, [this](beast::error_code ec, size_t) { onRead(ec); });
    });
  }

  void onRead(beast::error_code ec) {
    if (ec) {
      if (close_requested) return fail("closed by the client");
      if (ec != websocket::error::closed) return fail("reading: " + ec.message());
      websocket::close_reason reason;
      withWebSocket([&](auto& stream) { reason = stream.reason(); });
      return fail(describeClose(reason));
    }
    rmap::v1::ServerMessage message;
    const bool parsed = message.ParseFromArray(read_buffer.data().data(), static_cast<int>(read_buffer.size()));
    read_buffer.consume(read_buffer.size());
    if (!parsed) return fail("the server sent a frame that is not a ServerMessage");
    dispatch(message);
    if (!aborted) startRead();
  }

  void dispatch(const rmap::v1::ServerMessage& message) {
    switch (message.body_case()) {
      case rmap::v1::ServerMessage::kWelcome: {
        {
          std::lock_guard lock(mutex);
          if (state != State::connecting) break;  // a second Welcome means nothing
          welcome = message.welcome();
          // Never below a seq this client sent before: messages of a dropped stream
          // may still be committing, and a new message under their seq would be
          // taken for a duplicate and dropped.
          next_seq = std::max(next_seq, message.welcome().last_durable_seq() + 1);
          state = State::open;
        }
        cv.notify_all();
        break;
      }
      case rmap::v1::ServerMessage::kAck: {
        const auto& ack = message.ack();
        std::optional<std::chrono::nanoseconds> latency;
        {
          std::lock_guard lock(mutex);
          if (const auto it = in_flight.find(ack.seq()); it != in_flight.end()) latency = Clock::now() - it->second;
        }
        if (!latency) break;  // a repeat: it answers nothing in flight
        // The callback runs before the ack counts, so whoever waitAllAcked() lets
        // go has seen the callbacks of everything it waited for.
        if (ack_callback) ack_callback(ack, *latency);
        {
          std::lock_guard lock(mutex);
          in_flight.erase(ack.seq());
          ++acked;
          last_acked = std::max(last_acked, ack.seq());
        }
        cv.notify_all();
        break;
      }
      case rmap::v1::ServerMessage::kPose:
        if (pose_callback) pose_callback(message.pose());
        break;
      case rmap::v1::ServerMessage::kError: {
        const auto& error = message.error();
        if (error_callback) error_callback(error);  // first, as for acks
        bool ends_session = false;
        {
          std::lock_guard lock(mutex);
          last_error = error;
          if (error.seq() != 0) in_flight.erase(error.seq());  // answered, even if refused
          // Before Welcome any error refuses the session.
          ends_session = error.fatal() || state == State::connecting;
        }
        cv.notify_all();
        if (ends_session) fail("server error " + error.code() + ": " + error.message());
        break;
      }
      case rmap::v1::ServerMessage::BODY_NOT_SET:
        break;  // a newer server's message kind: nothing to do with it
    }
  }

  void enqueue(Frame frame) {
    if (aborted || close_requested) return;  // the session is over; the frame stays unacknowledged
    write_queue.push_back(std::move(frame));
    if (!writing) writeNext();
  }

  void writeNext() {
    if (write_queue.empty() || aborted) {
      writing = false;
      if (close_requested && !aborted) startClose();
      return;
    }
    writing = true;
    withWebSocket([&](auto& stream) {
      stream.binary(write_queue.front().binary);
      stream.async_write(asio::buffer(write_queue.front().bytes), [this](beast::error_code ec, size_t) {
        write_queue.pop_front();
        if (ec) {
          write_queue.clear();
          writing = false;
          return fail("writing: " + ec.message());
        }
        writeNext();
      });
    });
  }

  /// Normal closure once queued frames are out.
  void requestClose() {
    close_requested = true;
    bool open = false;
    if (ws || wss) withWebSocket([&](auto& stream) { open = stream.is_open(); });
    if (aborted || !open) return abort();
    if (!writing) startClose();
  }

  void startClose() {
    withWebSocket([&](auto& stream) {
      stream.async_close(websocket::close_code::normal, [this](beast::error_code) { abort(); });
    });
  }

  // ------------------------------------------------------------- caller side

  /// Posts an abort, joins the I/O thread and runs whatever it left queued.
  void shutdown() {
    if (!io_thread.joinable()) return;
    asio::post(ioc, [this] { abort(); });
    io_thread.join();
    ioc.restart();
    ioc.run();  // handlers posted after the thread stopped (they only find a closed socket)
    std::lock_guard lock(mutex);
    if (state != State::closed) {
      state = State::closed;
      if (failure.empty()) failure = "closed by the client";
    }
  }

  /// Waits (bounded) for the I/O thread to finish on its own, then shuts down.
  void close() {
    {
      std::lock_guard lock(mutex);
      if (!io_thread.joinable()) return;
      if (state == State::connecting || state == State::open) state = State::closing;
    }
    cv.notify_all();
    asio::post(ioc, [this] { requestClose(); });
    {
      std::unique_lock lock(mutex);
      cv.wait_for(lock, options.timeout, [this] { return !io_running; });
    }
    shutdown();
  }

  void post(Frame frame) {
    asio::post(ioc, [this, frame = std::move(frame)]() mutable { enqueue(std::move(frame)); });
  }

  /// send() (the next seq) or resend() (`keep_seq`: the message's own).
  uint64_t send(rmap::v1::RobotMessage message, bool keep_seq) {
    std::lock_guard send_lock(send_mutex);
    std::unique_lock lock(mutex);
    const bool room = cv.wait_for(lock, options.timeout, [this] {
      return state != State::open || in_flight.size() < options.max_in_flight;
    });
    if (state != State::open) throw ClientError(closedMessage());
    if (!room) {
      throw ClientError("timed out after " + std::to_string(options.timeout.count()) + " ms waiting for acks (" +
                        std::to_string(in_flight.size()) + " in flight)");
    }
    const uint64_t seq = keep_seq ? message.seq() : next_seq;
    const uint64_t max_frame = welcome->max_frame_bytes();
    lock.unlock();  // serialising a large cloud takes a while; acks may come in meanwhile

    message.set_seq(seq);
    std::string bytes = message.SerializeAsString();
    if (max_frame != 0 && bytes.size() > max_frame) {
      throw ClientError("message of " + std::to_string(bytes.size()) + " bytes exceeds the server's limit of " +
                        std::to_string(max_frame));
    }
    lock.lock();
    if (state != State::open) throw ClientError(closedMessage());
    in_flight.emplace(seq, Clock::now());
    next_seq = std::max(next_seq, seq + 1);
    last_sent = std::max(last_sent, seq);
    lock.unlock();
    post({std::move(bytes), true});
    return seq;
  }

  /// For send() on a session that is not open; call with `mutex` held.
  std::string closedMessage() const {
    if (state == State::closing) return "connection to " + options.server_url + " is closing";
    if (state == State::idle) return "not connected to " + options.server_url;
    return "connection to " + options.server_url + " closed: " + failure;
  }
};

RobotClient::RobotClient(RobotClientOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {}

RobotClient::~RobotClient() { close(); }

void RobotClient::onAck(AckCallback callback) { impl_->ack_callback = std::move(callback); }
void RobotClient::onPose(PoseCallback callback) { impl_->pose_callback = std::move(callback); }
void RobotClient::onError(ErrorCallback callback) { impl_->error_callback = std::move(callback); }

rmap::v1::Welcome RobotClient::connect() {
  Impl& d = *impl_;
  std::lock_guard send_lock(d.send_mutex);
  {
    std::lock_guard lock(d.mutex);
    if (d.state == Impl::State::connecting || d.state == Impl::State::open || d.state == Impl::State::closing) {
      throw ClientError("already connected to " + d.options.server_url);
    }
  }
  d.shutdown();  // a previous session's thread, if any

  // Fresh session: the I/O thread is not running, so its objects are ours here.
  d.resolver.emplace(d.ioc);
  d.ws.reset();
  d.wss.reset();
  if (d.tls) {
    d.wss.emplace(d.ioc, *d.tls);
  } else {
    d.ws.emplace(d.ioc);
  }
  d.read_buffer.clear();
  d.upgrade_response = websocket::response_type();
  d.write_queue.clear();
  d.writing = d.close_requested = d.aborted = false;
  {
    std::lock_guard lock(d.mutex);
    d.state = Impl::State::connecting;
    d.io_running = true;
    d.failure.clear();
    d.welcome.reset();
    d.last_error.reset();
    d.in_flight.clear();
    d.last_sent = d.last_acked = d.acked = 0;
  }
  d.ioc.restart();
  asio::post(d.ioc, [&d] { d.startConnect(); });
  d.io_thread = std::thread([&d] {
    d.ioc.run();
    {
      std::lock_guard lock(d.mutex);
      d.io_running = false;
    }
    d.cv.notify_all();
  });

  std::unique_lock lock(d.mutex);
  d.cv.wait_for(lock, d.options.timeout, [&d] { return d.state != Impl::State::connecting; });
  if (d.state == Impl::State::open) return *d.welcome;
  const std::string why = d.state == Impl::State::connecting
                              ? "timed out after " + std::to_string(d.options.timeout.count()) + " ms (" + d.stage + ")"
                              : d.failure;
  lock.unlock();
  d.shutdown();
  throw ClientError("connecting to " + d.options.server_url + ": " + why);
}

uint64_t RobotClient::send(rmap::v1::RobotMessage message) { return impl_->send(std::move(message), false); }

uint64_t RobotClient::resend(rmap::v1::RobotMessage message) {
  if (message.seq() == 0) throw ClientError("resend needs the message's original seq, not 0");
  return impl_->send(std::move(message), true);
}

void RobotClient::sendRaw(const std::string& bytes, bool binary) {
  Impl& d = *impl_;
  std::lock_guard send_lock(d.send_mutex);
  {
    std::lock_guard lock(d.mutex);
    if (d.state != Impl::State::open) throw ClientError(d.closedMessage());
  }
  d.post({bytes, binary});
}

bool RobotClient::waitAllAcked(std::chrono::milliseconds timeout) {
  Impl& d = *impl_;
  std::unique_lock lock(d.mutex);
  d.cv.wait_for(lock, timeout, [&d] { return d.in_flight.empty() || d.state != Impl::State::open; });
  return d.in_flight.empty();
}

uint64_t RobotClient::lastSentSeq() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->last_sent;
}

uint64_t RobotClient::lastAckedSeq() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->last_acked;
}

uint64_t RobotClient::ackedCount() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->acked;
}

bool RobotClient::connected() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->state == Impl::State::open;
}

std::optional<rmap::v1::Error> RobotClient::lastError() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->last_error;
}

void RobotClient::close() { impl_->close(); }

}  // namespace rmap::client
