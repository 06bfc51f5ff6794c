#pragma once
/// @file fake_robot_server.h
/// A loopback stand-in for rmapd's robot stream (/v1/stream/robot) for the
/// client tests: checks Hello, answers Welcome, acknowledges data messages
/// (optionally late, never, or with an Error), can refuse the upgrade with
/// 401 and a JSON body, and records what it received. One I/O thread runs
/// everything, so stopping it is a plain io_context::stop().

#include <algorithm>
#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "rmap/v1/robot_stream.pb.h"

namespace rmap::client::test {

struct FakeRobotServerOptions {
  /// Welcome::last_durable_seq is the larger of this and the robot's highest seq acked so far.
  uint64_t last_durable_seq = 0;
  bool welcome = true;                     ///< false: never answer Hello
  bool ack = true;                         ///< false: never acknowledge
  std::chrono::milliseconds ack_delay{0};  ///< each ack leaves this long after its message arrived
  bool poses = false;                      ///< send a PoseEstimate (a cloud's sensor pose, a scan's odometry) before each ack
  uint64_t error_seq = 0;                  ///< answer this seq with an Error instead of an Ack (0: none)
  bool error_fatal = false;                ///< that Error is fatal: the session closes after it
  bool refuse_upgrade = false;             ///< answer every upgrade with 401 and a JSON error
  std::string required_token;              ///< when set, upgrades without "Bearer <token>" get 401
};

class FakeRobotServer {
 public:
  static constexpr const char* kRefusal = "missing or unknown bearer token";

  explicit FakeRobotServer(FakeRobotServerOptions options = {})
      : options_(std::move(options)), acceptor_(ioc_, {boost::asio::ip::make_address("127.0.0.1"), 0}) {
    accept();
    thread_ = std::thread([this] { ioc_.run(); });
  }
  ~FakeRobotServer() {
    ioc_.stop();
    thread_.join();
  }
  FakeRobotServer(const FakeRobotServer&) = delete;
  FakeRobotServer& operator=(const FakeRobotServer&) = delete;

  std::string url() const { return "ws://127.0.0.1:" + std::to_string(acceptor_.local_endpoint().port()); }

  std::vector<rmap::v1::Hello> hellos() const {
    std::lock_guard lock(mutex_);
    return hellos_;
  }
  /// Data messages (all sessions) in arrival order.
  std::vector<rmap::v1::RobotMessage> messages() const {
    std::lock_guard lock(mutex_);
    return messages_;
  }
  /// Authorization header of every upgrade request ("" when absent).
  std::vector<std::string> authorizations() const {
    std::lock_guard lock(mutex_);
    return authorizations_;
  }
  /// Most data messages of one session received but not yet answered.
  size_t maxOutstanding() const {
    std::lock_guard lock(mutex_);
    return max_outstanding_;
  }
  size_t unparsableFrames() const {
    std::lock_guard lock(mutex_);
    return unparsable_;
  }
  /// Sessions the client ended with a WebSocket close frame.
  size_t cleanCloses() const {
    std::lock_guard lock(mutex_);
    return clean_closes_;
  }

 private:
  using tcp = boost::asio::ip::tcp;
  using error_code = boost::beast::error_code;
  using Stream = boost::beast::websocket::stream<tcp::socket>;

  class Session : public std::enable_shared_from_this<Session> {
   public:
    Session(FakeRobotServer& server, tcp::socket socket) : server_(server), socket_(std::move(socket)) {}

    void start() {
      namespace http = boost::beast::http;
      http::async_read(socket_, buffer_, request_, [self = shared_from_this()](error_code ec, size_t) {
        if (!ec) self->onRequest();
      });
    }

   private:
    void onRequest() {
      namespace http = boost::beast::http;
      const std::string authorization(request_[http::field::authorization]);
      const FakeRobotServerOptions& o = server_.options_;
      {
        std::lock_guard lock(server_.mutex_);
        server_.authorizations_.push_back(authorization);
      }
      if (o.refuse_upgrade || (!o.required_token.empty() && authorization != "Bearer " + o.required_token)) {
        auto response = std::make_shared<http::response<http::string_body>>(http::status::unauthorized, 11);
        response->set(http::field::content_type, "application/json");
        response->body() = std::string(R"({"error":{"code":"unauthorized","message":")") + kRefusal + "\"}}";
        response->keep_alive(false);
        response->prepare_payload();
        http::async_write(socket_, *response, [self = shared_from_this(), response](error_code, size_t) {
          error_code ignored;
          self->socket_.shutdown(tcp::socket::shutdown_both, ignored);
        });
        return;
      }
      error_code ignored;
      socket_.set_option(tcp::no_delay(true), ignored);  // small acks must not wait for Nagle
      ws_.emplace(std::move(socket_));
      ws_->binary(true);
      ws_->async_accept(request_, [self = shared_from_this()](error_code ec) {
        if (!ec) self->read();
      });
    }

    void read() {
      ws_->async_read(buffer_, [self = shared_from_this()](error_code ec, size_t) {
        if (!ec) return self->onMessage();
        if (ec == boost::beast::websocket::error::closed) {
          std::lock_guard lock(self->server_.mutex_);
          ++self->server_.clean_closes_;
        }
      });
    }

    void onMessage() {
      rmap::v1::RobotMessage message;
      const bool parsed = message.ParseFromArray(buffer_.data().data(), static_cast<int>(buffer_.size()));
      buffer_.consume(buffer_.size());
      const FakeRobotServerOptions& o = server_.options_;
      if (!parsed) {
        {
          std::lock_guard lock(server_.mutex_);
          ++server_.unparsable_;
        }
        reply(error("invalid_message", "not a RobotMessage", 0, false));
      } else if (!hello_seen_) {
        if (!message.has_hello() || message.seq() != 0) return reply(error("expected_hello", "Hello first", 0, true));
        hello_seen_ = true;
        robot_id_ = message.hello().robot_id();
        rmap::v1::ServerMessage welcome;
        rmap::v1::Welcome& w = *welcome.mutable_welcome();
        w.set_session_id("fake-session");
        w.set_robot_id(message.hello().robot_id());
        w.set_map(message.hello().map());
        w.set_resolution_m(message.hello().resolution_m());
        w.set_max_frame_bytes(64u << 20);
        w.set_server_version("fake");
        {
          std::lock_guard lock(server_.mutex_);
          server_.hellos_.push_back(message.hello());
          w.set_last_durable_seq(std::max(o.last_durable_seq, server_.highest_acked_[message.hello().robot_id()]));
        }
        if (o.welcome) reply(welcome);
      } else {
        {
          std::lock_guard lock(server_.mutex_);
          server_.messages_.push_back(message);
          ++outstanding_;
          server_.max_outstanding_ = std::max(server_.max_outstanding_, outstanding_);
        }
        answer(message);
      }
      read();
    }

    void answer(const rmap::v1::RobotMessage& message) {
      const FakeRobotServerOptions& o = server_.options_;
      if (message.seq() == o.error_seq) {
        answered(message.seq(), false);
        reply(error("invalid_message", "refused by the fake", message.seq(), o.error_fatal));
        return;
      }
      if (!o.ack) return;
      auto timer = std::make_shared<boost::asio::steady_timer>(ws_->get_executor(), o.ack_delay);
      timer->async_wait([self = shared_from_this(), timer, message](error_code) {
        if (self->server_.options_.poses && message.has_cloud()) {
          rmap::v1::ServerMessage pose;
          pose.mutable_pose()->set_seq(message.seq());
          pose.mutable_pose()->set_stamp_ns(message.cloud().stamp_ns());
          *pose.mutable_pose()->mutable_pose() = message.cloud().sensor_pose();
          self->reply(pose);
        }
        if (self->server_.options_.poses && message.has_scan() && message.scan().has_odometry()) {
          const rmap::v1::Pose2& odometry = message.scan().odometry();
          rmap::v1::ServerMessage pose;
          pose.mutable_pose()->set_seq(message.seq());
          pose.mutable_pose()->set_stamp_ns(message.scan().stamp_ns());
          rmap::v1::Pose3& p = *pose.mutable_pose()->mutable_pose();
          p.mutable_position_m()->set_x(odometry.x_m());
          p.mutable_position_m()->set_y(odometry.y_m());
          p.mutable_orientation()->set_w(std::cos(odometry.theta_rad() / 2));
          p.mutable_orientation()->set_z(std::sin(odometry.theta_rad() / 2));
          self->reply(pose);
        }
        rmap::v1::ServerMessage ack;
        ack.mutable_ack()->set_seq(message.seq());
        self->answered(message.seq(), true);
        self->reply(ack);
      });
    }

    void answered(uint64_t seq, bool acked) {
      std::lock_guard lock(server_.mutex_);
      --outstanding_;
      if (acked) server_.highest_acked_[robot_id_] = std::max(server_.highest_acked_[robot_id_], seq);
    }

    static rmap::v1::ServerMessage error(const std::string& code, const std::string& text, uint64_t seq, bool fatal) {
      rmap::v1::ServerMessage m;
      m.mutable_error()->set_code(code);
      m.mutable_error()->set_message(text);
      m.mutable_error()->set_seq(seq);
      m.mutable_error()->set_fatal(fatal);
      return m;
    }

    /// Queues a frame; a fatal Error closes the session once written.
    void reply(const rmap::v1::ServerMessage& message) {
      close_after_ = close_after_ || (message.has_error() && message.error().fatal());
      out_.push_back(message.SerializeAsString());
      if (!writing_) writeNext();
    }

    void writeNext() {
      if (out_.empty()) {
        writing_ = false;
        if (close_after_) {
          ws_->async_close(boost::beast::websocket::close_code::policy_error,
                           [self = shared_from_this()](error_code) {});
        }
        return;
      }
      writing_ = true;
      ws_->async_write(boost::asio::buffer(out_.front()), [self = shared_from_this()](error_code ec, size_t) {
        self->out_.pop_front();
        if (!ec) self->writeNext();
      });
    }

    FakeRobotServer& server_;
    tcp::socket socket_;
    std::optional<Stream> ws_;
    boost::beast::flat_buffer buffer_;
    boost::beast::http::request<boost::beast::http::string_body> request_;
    std::deque<std::string> out_;
    bool writing_ = false;
    bool close_after_ = false;
    bool hello_seen_ = false;
    std::string robot_id_;
    size_t outstanding_ = 0;  ///< guarded by server_.mutex_
  };

  void accept() {
    acceptor_.async_accept([this](error_code ec, tcp::socket socket) {
      if (ec) return;
      std::make_shared<Session>(*this, std::move(socket))->start();
      accept();
    });
  }

  FakeRobotServerOptions options_;
  boost::asio::io_context ioc_;
  tcp::acceptor acceptor_;
  std::thread thread_;
  mutable std::mutex mutex_;
  std::vector<rmap::v1::Hello> hellos_;
  std::vector<rmap::v1::RobotMessage> messages_;
  std::vector<std::string> authorizations_;
  size_t max_outstanding_ = 0;
  size_t unparsable_ = 0;
  size_t clean_closes_ = 0;
  std::map<std::string, uint64_t> highest_acked_;  ///< per robot id, across sessions
};

}  // namespace rmap::client::test
