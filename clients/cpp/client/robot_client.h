#pragma once
/// @file robot_client.h
/// A robot's connection to rmapd: WebSocket `/v1/stream/robot`, protobuf
/// frames (proto/rmap/v1/robot_stream.proto). Sends Hello, then data messages
/// with increasing sequence numbers; a reader thread receives acks, pose
/// estimates and errors. At most `max_in_flight` messages are unacknowledged:
/// send() blocks beyond that, which paces a robot to what the server makes durable.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>

#include "rmap/v1/robot_stream.pb.h"

namespace rmap::client {

class ClientError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Parsed ws[s]://host[:port][/path] or http[s]://host[:port][/path].
struct Endpoint {
  std::string host;
  std::string port;  ///< 80, or 443 with TLS, when absent
  std::string path;  ///< "/" when absent
  bool tls = false;  ///< wss:// or https://
  /// @throws ClientError for anything else
  static Endpoint parse(const std::string& url);
};

struct RobotClientOptions {
  /// ws:// or wss:// (TLS); the path is /v1/stream/robot
  std::string server_url = "ws://127.0.0.1:8080";
  std::string token;                               ///< sent as Authorization: Bearer when set
  /// wss:// only: PEM CA certificates the server's certificate must chain to;
  /// empty = the system's trust store. The certificate must also name the
  /// URL's host (DNS name, or IP address in its subjectAltName).
  std::string ca_file;
  rmap::v1::Hello hello;                           ///< robot id, map, sensors
  size_t max_in_flight = 64;
  std::chrono::milliseconds timeout{10000};        ///< connect, welcome and send() waits
};

class RobotClient {
 public:
  using AckCallback = std::function<void(const rmap::v1::Ack& ack, std::chrono::nanoseconds latency)>;
  using PoseCallback = std::function<void(const rmap::v1::PoseEstimate& pose)>;
  using ErrorCallback = std::function<void(const rmap::v1::Error& error)>;

  explicit RobotClient(RobotClientOptions options);
  ~RobotClient();  ///< closes
  RobotClient(const RobotClient&) = delete;
  RobotClient& operator=(const RobotClient&) = delete;

  /// Callbacks run on the reader thread; set them before connect(). They run
  /// before the message counts as answered (so waitAllAcked() returning true
  /// means every callback of those messages has run) and must not call
  /// send(), waitAllAcked() or close(): those wait for the reader thread.
  void onAck(AckCallback callback);
  void onPose(PoseCallback callback);
  void onError(ErrorCallback callback);

  /// Connects, sends Hello and waits for Welcome. Sequence numbers continue
  /// after Welcome::last_durable_seq, or after the highest seq this client
  /// sent in an earlier session if that is higher.
  /// @throws ClientError (refused upgrade with the HTTP status and body,
  ///         Error reply, timeout)
  rmap::v1::Welcome connect();

  /// Sets the next sequence number on `message`, sends it and returns that
  /// number. Blocks while max_in_flight messages are unacknowledged.
  /// @throws ClientError when the connection is closed or the wait times out
  uint64_t send(rmap::v1::RobotMessage message);
  /// Sends a message again with the seq it carries, e.g. one of an earlier
  /// session that was never acknowledged (API §5.10: the server acks it as a
  /// duplicate if it was stored after all). Tracked, blocking and throwing
  /// like send(); later send()s number after the highest seq sent.
  /// @throws ClientError also when the message's seq is 0
  uint64_t resend(rmap::v1::RobotMessage message);
  /// Sends raw bytes as one binary frame (tests of bad input).
  void sendRaw(const std::string& bytes, bool binary = true);

  /// Waits until every sent message is acknowledged.
  /// @return false on timeout or when the connection closed first
  bool waitAllAcked(std::chrono::milliseconds timeout);
  uint64_t lastSentSeq() const;
  /// Highest seq acknowledged in this session.
  uint64_t lastAckedSeq() const;
  uint64_t ackedCount() const;
  bool connected() const;
  /// Last Error received, if any.
  std::optional<rmap::v1::Error> lastError() const;
  /// Closes the WebSocket (normal closure) and joins the reader.
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rmap::client
