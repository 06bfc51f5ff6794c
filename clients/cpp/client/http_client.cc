// HttpClient: blocking HTTP/1.1 on one keep-alive connection, plain or TLS.
//
// The calls are asynchronous Beast operations run on the caller's thread with
// io_context::run_until(deadline): that is what gives every request a timeout
// (synchronous socket calls cannot time out).

#include "client/http_client.h"

#include <algorithm>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <cctype>
#include <limits>
#include <optional>

#include "client/robot_client.h"
#include "client/tls_client.h"

namespace rmap::client {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
using tcp = asio::ip::tcp;
using Clock = std::chrono::steady_clock;

std::string lower(beast::string_view s) {
  std::string out(s.data(), s.size());
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

/// Errors meaning the server closed a kept-alive connection before reading the
/// request: the request can be sent again on a new connection. (rmapd ends
/// TLS connections without close_notify: stream_truncated.)
bool staleConnection(const beast::error_code& ec) {
  return ec == http::error::end_of_stream || ec == asio::error::eof || ec == asio::error::connection_reset ||
         ec == asio::error::broken_pipe || ec == asio::ssl::error::stream_truncated;
}

}  // namespace

std::string HttpResponse::header(const std::string& lower_name) const {
  const auto it = headers.find(lower_name);
  return it == headers.end() ? std::string() : it->second;
}

struct HttpClient::Impl {
  Impl(const std::string& base_url, std::string bearer, std::chrono::milliseconds limit, const std::string& ca_file)
      : endpoint(Endpoint::parse(base_url)), token(std::move(bearer)), timeout(limit) {
    host_header = endpoint.host.find(':') != std::string::npos ? "[" + endpoint.host + "]" : endpoint.host;
    host_header += ":" + endpoint.port;
    if (endpoint.tls) tls = makeClientTlsContext(ca_file);
    newStream();
  }

  Endpoint endpoint;
  std::string token;
  std::chrono::milliseconds timeout;
  std::string host_header;
  std::shared_ptr<asio::ssl::context> tls;  ///< https:// only
  asio::io_context ioc;
  tcp::resolver resolver{ioc};
  // Exactly one is set. A TLS session does not survive its connection, so
  // each connection gets a fresh stream.
  std::optional<beast::tcp_stream> plain;
  std::optional<TlsTcpStream> secure;
  beast::flat_buffer buffer;
  bool connected = false;

  void newStream() {
    if (tls) {
      secure.emplace(ioc, *tls);
    } else {
      plain.emplace(ioc);
    }
  }

  beast::tcp_stream& transport() { return secure ? beast::get_lowest_layer(*secure) : *plain; }

  /// Runs `operation` on the stream the scheme uses.
  template <class Operation>
  void withStream(Operation&& operation) {
    if (secure) {
      operation(*secure);
    } else {
      operation(*plain);
    }
  }

  void disconnect() {
    beast::error_code ignored;
    transport().socket().shutdown(tcp::socket::shutdown_both, ignored);
    transport().close();
    buffer.clear();
    connected = false;
  }

  /// Runs the operation started before the call until it sets `done`.
  /// @throws ClientError when the deadline passes first (the connection is dropped)
  void await(const bool& done, Clock::time_point deadline, const std::string& what) {
    ioc.restart();
    ioc.run_until(deadline);
    if (done) return;
    resolver.cancel();
    disconnect();
    ioc.restart();
    ioc.run();  // lets the cancelled handlers finish
    throw ClientError(what + " timed out after " + std::to_string(timeout.count()) + " ms");
  }

  void connect(Clock::time_point deadline, const std::string& what) {
    bool done = false;
    beast::error_code ec;
    tcp::resolver::results_type results;
    resolver.async_resolve(endpoint.host, endpoint.port,
                           [&](beast::error_code e, const tcp::resolver::results_type& r) {
                             ec = e;
                             results = r;
                             done = true;
                           });
    await(done, deadline, what);
    if (ec) throw ClientError(what + ": resolving " + endpoint.host + ": " + ec.message());
    newStream();
    done = false;
    transport().async_connect(results, [&](beast::error_code e, const tcp::endpoint&) {
      ec = e;
      done = true;
    });
    await(done, deadline, what);
    if (ec) {
      disconnect();
      throw ClientError(what + ": connecting to " + host_header + ": " + ec.message());
    }
    transport().socket().set_option(tcp::no_delay(true), ec);
    if (secure) {
      prepareTlsStream(*secure, endpoint.host);
      done = false;
      secure->async_handshake(asio::ssl::stream_base::client, [&](beast::error_code e) {
        ec = e;
        done = true;
      });
      await(done, deadline, what);
      if (ec) {
        disconnect();
        throw ClientError(what + ": TLS handshake with " + host_header + ": " + ec.message());
      }
    }
    connected = true;
  }

  /// Writes the request and reads the response on the current connection.
  beast::error_code exchange(const http::request<http::string_body>& request,
                             http::response_parser<http::string_body>& parser, Clock::time_point deadline,
                             const std::string& what) {
    bool done = false;
    beast::error_code ec;
    withStream([&](auto& stream) {
      http::async_write(stream, request, [&](beast::error_code e, size_t) {
        ec = e;
        done = true;
      });
    });
    await(done, deadline, what);
    if (ec) return ec;
    done = false;
    withStream([&](auto& stream) {
      http::async_read(stream, buffer, parser, [&](beast::error_code e, size_t) {
        ec = e;
        done = true;
      });
    });
    await(done, deadline, what);
    return ec;
  }

  HttpResponse request(http::verb verb, const std::string& target, const std::string* body,
                       const std::string& content_type, const std::map<std::string, std::string>& headers) {
    const std::string what = std::string(http::to_string(verb)) + " " + target;
    const auto deadline = Clock::now() + timeout;
    http::request<http::string_body> request{verb, target, 11};
    request.set(http::field::host, host_header);
    request.set(http::field::user_agent, "rmap-client");
    if (!token.empty()) request.set(http::field::authorization, "Bearer " + token);
    if (body) {
      request.set(http::field::content_type, content_type);
      request.body() = *body;
    }
    for (const auto& [name, value] : headers) request.set(name, value);
    request.prepare_payload();

    // Bulk responses (tiles, map downloads) can be large; this only stops a runaway body.
    constexpr uint64_t kMaxBodyBytes = uint64_t{1} << 32;
    for (int attempt = 0;; ++attempt) {
      const bool reused = connected;
      if (!connected) connect(deadline, what);
      http::response_parser<http::string_body> parser;
      parser.body_limit(kMaxBodyBytes);
      const beast::error_code ec = exchange(request, parser, deadline, what);
      if (!ec) {
        http::response<http::string_body> response = parser.release();
        if (!response.keep_alive()) disconnect();
        return convert(response);
      }
      disconnect();
      // One retry, and only when an idle kept-alive connection had been closed by the server.
      if (!(reused && attempt == 0 && staleConnection(ec))) throw ClientError(what + ": " + ec.message());
    }
  }

  static HttpResponse convert(http::response<http::string_body>& response) {
    HttpResponse out;
    out.status = static_cast<int>(response.result_int());
    out.body = std::move(response.body());
    for (const auto& field : response) {
      std::string& value = out.headers[lower(field.name_string())];
      if (!value.empty()) value += ", ";  // repeated fields combine as a list (RFC 9110 §5.3)
      value += std::string(field.value());
    }
    return out;
  }
};

HttpClient::HttpClient(const std::string& base_url, std::string token, std::chrono::milliseconds timeout,
                       const std::string& ca_file)
    : impl_(std::make_unique<Impl>(base_url, std::move(token), timeout, ca_file)) {}

HttpClient::~HttpClient() { impl_->disconnect(); }

HttpResponse HttpClient::get(const std::string& target, const std::map<std::string, std::string>& headers) {
  return impl_->request(http::verb::get, target, nullptr, {}, headers);
}

HttpResponse HttpClient::post(const std::string& target, const std::string& body, const std::string& content_type,
                              const std::map<std::string, std::string>& headers) {
  return impl_->request(http::verb::post, target, &body, content_type, headers);
}

}  // namespace rmap::client
