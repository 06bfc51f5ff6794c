#pragma once
/// @file robot_session.h
/// One robot's WebSocket stream: Hello → Welcome, then every data message is
/// checked, made durable through the group committer, applied to the map in
/// log order and acknowledged. Bad messages get an Error and change nothing.

#include <atomic>
#include <chrono>
#include <memory>
#include <mutex>
#include <string>

#include "app/auth.h"
#include "net/service.h"
#include "rmap/v1/robot_stream.pb.h"

namespace rmap::app {

class MappingService;
class MapWorker;

class RobotSession : public net::WsHandler, public std::enable_shared_from_this<RobotSession> {
 public:
  RobotSession(MappingService& service, Principal principal);
  ~RobotSession() override;

  void onOpen(std::shared_ptr<net::WsConnection> connection) override;
  void onMessage(std::string data, bool binary) override;
  void onClose() override;

  /// Queues a 2D SLAM estimate to the robot. @return false when it was dropped (closed, queue full)
  bool sendPoseEstimate(const v1::PoseEstimate& estimate);
  /// Ends the stream with a fatal error (e.g. the robot connected again elsewhere).
  void closeWithError(const std::string& code, const std::string& message);
  const std::string& robotId() const { return robot_id_; }
  /// Unix time (ns) of the latest data message accepted on this stream, 0 before the first.
  int64_t lastSeenNs() const { return last_seen_ns_.load(std::memory_order_relaxed); }

 private:
  void handleHello(const v1::Hello& hello);
  void handleData(std::string frame, std::shared_ptr<v1::RobotMessage> message,
                  std::chrono::steady_clock::time_point received);
  /// Called once the message is durable (or failed) and applied.
  void finish(uint64_t seq, bool duplicate, std::chrono::steady_clock::time_point received, const char* error);
  void sendError(const std::string& code, const std::string& message, uint64_t seq, bool fatal);
  bool send(const v1::ServerMessage& message);
  bool takeRateToken();

  MappingService& service_;
  Principal principal_;
  std::shared_ptr<net::WsConnection> connection_;
  std::string robot_id_;
  std::shared_ptr<MapWorker> map_;
  std::atomic<size_t> in_flight_{0};
  std::atomic<bool> paused_{false};
  std::atomic<bool> closed_{false};
  std::atomic<int64_t> last_seen_ns_{0};  ///< one relaxed store per message: no store write on this path
  double rate_tokens_ = 0.0;
  std::chrono::steady_clock::time_point rate_refill_;
};

}  // namespace rmap::app
