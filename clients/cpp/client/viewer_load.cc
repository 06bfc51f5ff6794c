// ViewerLoad: every viewer on one I/O thread, asynchronous Beast reads.

#include "client/viewer_load.h"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <string_view>
#include <thread>

#include "client/robot_client.h"

namespace rmap::client {

namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

/// The value of the last "type" key of a viewer frame: rmapd's JSON has its keys
/// sorted, and the frames counted (tiles, poses, resync) have no key after "type".
std::string_view frameType(std::string_view frame) {
  constexpr std::string_view kKey = "\"type\":\"";
  const size_t at = frame.rfind(kKey);
  if (at == std::string_view::npos) return {};
  const size_t begin = at + kKey.size();
  const size_t end = frame.find('"', begin);
  return end == std::string_view::npos ? std::string_view() : frame.substr(begin, end - begin);
}

}  // namespace

struct ViewerLoad::Impl {
  struct Viewer {
    explicit Viewer(asio::io_context& io, int index, bool stalled) : ws(io), index(index), stalled(stalled) {}
    websocket::stream<beast::tcp_stream> ws;
    beast::flat_buffer buffer;
    ViewerCounts counts;
    int index;
    bool stalled;
    bool open = false;
    std::string failure;
  };

  /// Connects and upgrades `viewer`. One address, not the resolver's list: connecting
  /// over a list reopens the socket for each, dropping a stalled viewer's buffer size.
  void open(Viewer& viewer, const tcp::endpoint& address) {
    beast::tcp_stream& stream = beast::get_lowest_layer(viewer.ws);
    stream.expires_after(options.timeout);
    if (viewer.stalled) {
      beast::error_code ec;
      stream.socket().open(address.protocol(), ec);
      if (!ec) stream.socket().set_option(asio::socket_base::receive_buffer_size(options.stalled_receive_buffer_bytes), ec);
      if (ec) {
        viewer.failure = "socket: " + ec.message();
        return;
      }
    }
    stream.async_connect(address, [this, &viewer](beast::error_code ec) {
      if (ec) {
        viewer.failure = "connect: " + ec.message();
        return;
      }
      beast::get_lowest_layer(viewer.ws).expires_never();  // the WebSocket's own timeouts from here
      viewer.ws.set_option(websocket::stream_base::timeout::suggested(beast::role_type::client));
      viewer.ws.set_option(websocket::stream_base::decorator([token = options.token](websocket::request_type& request) {
        if (!token.empty()) request.set(beast::http::field::authorization, "Bearer " + token);
      }));
      viewer.ws.async_handshake(host, "/v1/stream/viewer?map=" + options.map, [&viewer](beast::error_code ec) {
        if (ec) {
          viewer.failure = "handshake: " + ec.message();
          return;
        }
        viewer.open = true;
      });
    });
  }

  void read(Viewer& viewer) {
    viewer.ws.async_read(viewer.buffer, [this, &viewer](beast::error_code ec, size_t bytes) {
      if (ec) {
        if (!stopping) errors.push_back("viewer " + std::to_string(viewer.index) + ": " + ec.message());
        return;
      }
      ViewerCounts& c = viewer.counts;
      ++c.frames;
      c.bytes += bytes;
      const std::string_view type =
          frameType(std::string_view(static_cast<const char*>(viewer.buffer.data().data()), viewer.buffer.size()));
      c.tiles += type == "tiles";
      c.poses += type == "poses";
      c.resyncs += type == "resync";
      viewer.buffer.consume(viewer.buffer.size());
      read(viewer);
    });
  }

  ViewerLoadOptions options;
  std::string host;  ///< Host header
  asio::io_context io;
  std::vector<std::unique_ptr<Viewer>> viewers;
  std::thread thread;
  bool stopping = false;            ///< I/O thread only
  std::vector<std::string> errors;  ///< I/O thread only, until joined
  bool stopped = false;
};

ViewerLoad::ViewerLoad(const ViewerLoadOptions& options) : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.options = options;
  const Endpoint endpoint = Endpoint::parse(options.server_url);
  if (endpoint.tls) throw ClientError("ViewerLoad speaks plain ws:// only, not " + options.server_url);
  d.host = endpoint.host + ":" + endpoint.port;
  tcp::resolver resolver(d.io);
  const tcp::endpoint address = resolver.resolve(endpoint.host, endpoint.port).begin()->endpoint();
  for (int i = 0; i < options.reading + options.stalled; ++i) {
    d.viewers.push_back(std::make_unique<Impl::Viewer>(d.io, i, i >= options.reading));
    d.open(*d.viewers.back(), address);
  }
  d.io.run_for(options.timeout);  // returns as soon as every handshake is done
  for (const auto& viewer : d.viewers) {
    if (!viewer->open) {
      const std::string why = viewer->failure.empty() ? "timed out" : viewer->failure;
      throw ClientError("viewer " + std::to_string(viewer->index) + " of " + options.server_url + ": " + why);
    }
  }
  d.io.restart();
  for (const auto& viewer : d.viewers) {
    if (!viewer->stalled) d.read(*viewer);
  }
  d.thread = std::thread([&d] { d.io.run(); });
}

ViewerLoad::~ViewerLoad() {
  if (!impl_->stopped) stop();
}

ViewerLoadResult ViewerLoad::stop() {
  Impl& d = *impl_;
  d.stopped = true;
  asio::post(d.io, [&d] {
    d.stopping = true;
    for (const auto& viewer : d.viewers) {
      beast::error_code ignored;
      beast::get_lowest_layer(viewer->ws).socket().close(ignored);  // pending reads end with operation_aborted
    }
  });
  if (d.thread.joinable()) d.thread.join();
  ViewerLoadResult result;
  for (const auto& viewer : d.viewers) {
    if (!viewer->stalled) result.reading.push_back(viewer->counts);
  }
  result.errors = std::move(d.errors);
  return result;
}

}  // namespace rmap::client
