#include "net/server.h"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl/context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>
#include <algorithm>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include "net/http_session.h"
#include "net/server_state.h"

namespace rmap::net {
namespace {

namespace asio = boost::asio;
using tcp = asio::ip::tcp;
using boost::system::error_code;

/// After an accept error other than a cancel (typically EMFILE, which repeats
/// at once), wait this long instead of spinning.
constexpr std::chrono::milliseconds kAcceptRetryDelay{50};

std::string hostPort(const std::string& host, uint16_t port) {
  const bool ipv6 = host.find(':') != std::string::npos;
  return (ipv6 ? "[" + host + "]" : host) + ":" + std::to_string(port);
}

}  // namespace

struct Server::Impl {
  Impl(const ServerOptions& options, Service& service)
      : state(std::make_shared<ServerState>(options, service)),
        threads_wanted(std::max(1, options.io_threads)),
        io(threads_wanted),
        acceptor(asio::make_strand(io)),
        retry_timer(acceptor.get_executor()) {}

  /// Opens, binds and listens on the first resolved address that works.
  void listen() {
    const ServerOptions& options = state->options;
    const auto fail = [&](const error_code& ec) {
      throw std::runtime_error("cannot listen on " + hostPort(options.host, options.port) + ": " + ec.message());
    };
    error_code ec;
    tcp::resolver resolver(io);
    const auto endpoints = resolver.resolve(options.host, std::to_string(options.port),
                                            tcp::resolver::passive | tcp::resolver::numeric_service, ec);
    if (ec) fail(ec);
    for (const auto& entry : endpoints) {
      if (tryListen(entry.endpoint(), ec)) {
        port = acceptor.local_endpoint().port();
        return;
      }
    }
    fail(ec);
  }

  bool tryListen(const tcp::endpoint& endpoint, error_code& ec) {
    acceptor.open(endpoint.protocol(), ec);
    if (!ec) acceptor.set_option(tcp::acceptor::reuse_address(true), ec);
    if (!ec) acceptor.bind(endpoint, ec);
    if (!ec) acceptor.listen(asio::socket_base::max_listen_connections, ec);
    if (!ec) return true;
    error_code ignored;
    acceptor.close(ignored);
    return false;
  }

  /// Accepts each connection onto a strand of its own; runs on the
  /// acceptor's strand.
  void accept() {
    acceptor.async_accept(asio::make_strand(io),
                          [this](const error_code& ec, tcp::socket socket) { onAccept(ec, std::move(socket)); });
  }

  void onAccept(const error_code& ec, tcp::socket socket) {
    if (!acceptor.is_open()) return;  // stop() closed it
    if (ec) {
      retry_timer.expires_after(kAcceptRetryDelay);
      retry_timer.async_wait([this](const error_code& wait_ec) {
        if (!wait_ec) accept();
      });
      return;
    }
    if (state->connections.load() < state->options.max_connections) {
      // Replies are small and often come in pairs (a WebSocket frame, then
      // the next): with Nagle the second waits for the client's delayed ACK,
      // 40 ms on Linux. Failure only costs latency.
      error_code ignored;
      socket.set_option(tcp::no_delay(true), ignored);
      if (state->options.tls) {
        startHttpSession(TlsStream(std::move(socket), *state->options.tls), state);
      } else {
        startHttpSession(std::move(socket), state);
      }
    }  // else the socket closes right here
    accept();
  }

  std::shared_ptr<ServerState> state;
  const int threads_wanted;
  asio::io_context io;
  tcp::acceptor acceptor;  ///< on a strand: stop() closes it from another thread
  asio::steady_timer retry_timer;
  std::vector<std::thread> threads;
  uint16_t port = 0;
  std::mutex lifecycle;  ///< serialises start() and stop()
  bool started = false;
  bool stopped = false;
};

Server::Server(const ServerOptions& options, Service& service) : impl_(std::make_unique<Impl>(options, service)) {}

Server::~Server() { stop(); }

void Server::start() {
  std::lock_guard lock(impl_->lifecycle);
  if (impl_->started || impl_->stopped) throw std::logic_error("rmap::net::Server can start only once");
  impl_->listen();
  impl_->started = true;
  impl_->accept();
  for (int i = 0; i < impl_->threads_wanted; ++i) {
    impl_->threads.emplace_back([io = &impl_->io] { io->run(); });
  }
}

void Server::stop() {
  Impl& impl = *impl_;
  std::lock_guard lock(impl.lifecycle);
  if (impl.stopped) return;
  impl.stopped = true;
  if (!impl.started) return;
  asio::post(impl.acceptor.get_executor(), [&impl] {
    error_code ignored;
    impl.acceptor.close(ignored);
    impl.retry_timer.cancel();
  });
  for (const auto& session : impl.state->stopAll()) session->shutdown();
  // With the listener and every socket closed, no work is left and run()
  // returns; WsConnections still held by handlers are detached by then.
  for (auto& thread : impl.threads) thread.join();
  impl.threads.clear();
}

uint16_t Server::port() const { return impl_->port; }

size_t Server::connections() const { return impl_->state->connections.load(); }

size_t Server::webSocketConnections() const { return impl_->state->web_sockets.load(); }

}  // namespace rmap::net
