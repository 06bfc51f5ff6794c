#pragma once
/// @file fake_http_server.h
/// A tiny loopback HTTP/1.1 server for the HttpClient tests. Routes:
/// GET /hello → 200 text/plain "hello"; POST /echo → 200 with the request
/// body and content type; anything else → 404 with a JSON error. Every
/// response carries x-connection (1-based index of the accepted socket) and
/// x-authorization (the request's Authorization header). It counts accepted
/// connections and can drop or close connections after each response.

#include <atomic>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <memory>
#include <optional>
#include <string>
#include <thread>

namespace rmap::client::test {

class FakeHttpServer {
 public:
  enum class AfterResponse {
    keep_alive,      ///< a normal keep-alive server
    drop,            ///< closes the connection while announcing keep-alive (an idle-timeout race)
    announce_close,  ///< answers "Connection: close" and closes
  };

  explicit FakeHttpServer(AfterResponse after = AfterResponse::keep_alive)
      : after_(after), acceptor_(ioc_, {boost::asio::ip::make_address("127.0.0.1"), 0}) {
    accept();
    thread_ = std::thread([this] { ioc_.run(); });
  }
  ~FakeHttpServer() {
    ioc_.stop();
    thread_.join();
  }
  FakeHttpServer(const FakeHttpServer&) = delete;
  FakeHttpServer& operator=(const FakeHttpServer&) = delete;

  std::string url() const { return "http://127.0.0.1:" + std::to_string(acceptor_.local_endpoint().port()); }
  int acceptedConnections() const { return accepted_.load(); }

 private:
  using tcp = boost::asio::ip::tcp;
  using error_code = boost::beast::error_code;

  class Session : public std::enable_shared_from_this<Session> {
   public:
    Session(tcp::socket socket, int index, AfterResponse after)
        : socket_(std::move(socket)), index_(index), after_(after) {}

    void read() {
      parser_.emplace();
      parser_->body_limit(64u << 20);  // the default 1 MiB is too small for the bulk tests
      boost::beast::http::async_read(socket_, buffer_, *parser_, [self = shared_from_this()](error_code ec, size_t) {
        if (ec) return;
        self->request_ = self->parser_->release();
        self->respond();
      });
    }

   private:
    void respond() {
      namespace http = boost::beast::http;
      response_ = {};
      response_.version(11);
      if (request_.method() == http::verb::get && request_.target() == "/hello") {
        response_.result(http::status::ok);
        response_.set(http::field::content_type, "text/plain");
        response_.body() = "hello";
      } else if (request_.method() == http::verb::post && request_.target() == "/echo") {
        response_.result(http::status::ok);
        response_.set(http::field::content_type, request_[http::field::content_type]);
        response_.body() = request_.body();
      } else {
        response_.result(http::status::not_found);
        response_.set(http::field::content_type, "application/json");
        response_.body() = R"({"error":{"code":"not_found","message":"no such route"}})";
      }
      response_.set("x-connection", std::to_string(index_));
      response_.set("x-authorization", request_[http::field::authorization]);
      response_.keep_alive(after_ != AfterResponse::announce_close && request_.keep_alive());
      response_.prepare_payload();
      http::async_write(socket_, response_, [self = shared_from_this()](error_code ec, size_t) {
        if (ec) return;
        if (self->after_ == AfterResponse::keep_alive && self->response_.keep_alive()) return self->read();
        error_code ignored;
        self->socket_.shutdown(tcp::socket::shutdown_both, ignored);
        self->socket_.close(ignored);
      });
    }

    tcp::socket socket_;
    int index_;
    AfterResponse after_;
    boost::beast::flat_buffer buffer_;
    std::optional<boost::beast::http::request_parser<boost::beast::http::string_body>> parser_;
    boost::beast::http::request<boost::beast::http::string_body> request_;
    boost::beast::http::response<boost::beast::http::string_body> response_;
  };

  void accept() {
    acceptor_.async_accept([this](error_code ec, tcp::socket socket) {
      if (ec) return;
      std::make_shared<Session>(std::move(socket), ++accepted_, after_)->read();
      accept();
    });
  }

  AfterResponse after_;
  std::atomic<int> accepted_{0};
  boost::asio::io_context ioc_;
  tcp::acceptor acceptor_;
  std::thread thread_;
};

}  // namespace rmap::client::test
