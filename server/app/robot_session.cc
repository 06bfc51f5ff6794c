#include "app/robot_session.h"

#include <spdlog/spdlog.h>

#include "app/ingest.h"
#include "app/mapping_service.h"
#include "app/robot_sensors.h"
#include "app/wall_clock.h"

namespace rmap::app {

namespace {

using Clock = std::chrono::steady_clock;

std::string sensorsJson(const v1::Hello& hello) {
  nlohmann::json sensors = nlohmann::json::array();
  for (const v1::SensorDescription& s : hello.sensors()) {
    sensors.push_back({{"name", s.name()},
                       {"kind", v1::SensorDescription::Kind_Name(s.kind())},
                       {"model", s.model()}});
  }
  return sensors.dump();
}

}  // namespace

RobotSession::RobotSession(MappingService& service, Principal principal)
    : service_(service), principal_(std::move(principal)), rate_refill_(Clock::now()) {
  rate_tokens_ = service_.config().limits.max_messages_per_s_per_robot;
}

RobotSession::~RobotSession() = default;

void RobotSession::onOpen(std::shared_ptr<net::WsConnection> connection) { connection_ = std::move(connection); }

void RobotSession::onClose() {
  closed_ = true;
  if (!robot_id_.empty()) service_.robotDisconnected(robot_id_, this);
}

bool RobotSession::send(const v1::ServerMessage& message) {
  if (connection_ && connection_->send(message.SerializeAsString(), true)) return true;
  spdlog::debug("robot {}: reply dropped (send queue full or closed)", robot_id_);
  return false;
}

bool RobotSession::sendPoseEstimate(const v1::PoseEstimate& estimate) {
  v1::ServerMessage reply;
  *reply.mutable_pose() = estimate;
  return send(reply);
}

void RobotSession::sendError(const std::string& code, const std::string& message, uint64_t seq, bool fatal) {
  v1::ServerMessage reply;
  v1::Error* error = reply.mutable_error();
  error->set_code(code);
  error->set_message(message);
  error->set_seq(seq);
  error->set_fatal(fatal);
  send(reply);
  if (fatal && connection_) connection_->close(1008, code);
}

void RobotSession::closeWithError(const std::string& code, const std::string& message) {
  sendError(code, message, 0, true);
}

bool RobotSession::takeRateToken() {
  const double rate = service_.config().limits.max_messages_per_s_per_robot;
  const auto now = Clock::now();
  rate_tokens_ = std::min(rate, rate_tokens_ + rate * std::chrono::duration<double>(now - rate_refill_).count());
  rate_refill_ = now;
  if (rate_tokens_ < 1.0) return false;
  rate_tokens_ -= 1.0;
  return true;
}

void RobotSession::onMessage(std::string data, bool binary) {
  const auto received = Clock::now();
  Metrics& metrics = service_.metrics();
  metrics.messages_received.fetch_add(1, std::memory_order_relaxed);
  auto reject = [&](const std::string& code, const std::string& text, uint64_t seq, bool fatal) {
    metrics.messages_rejected.fetch_add(1, std::memory_order_relaxed);
    sendError(code, text, seq, fatal);
  };
  const RobotFrame frame = decodeRobotFrame(data, binary, robot_id_.empty() ? nullptr : &map_->map().grid(),
                                            service_.config().limits);
  if (!frame.message) return reject(frame.code, frame.problem, frame.seq, frame.fatal);
  if (robot_id_.empty()) return handleHello(frame.message->hello());
  // Before the rate limit and the store: a refusal here takes no token and leaves nothing behind.
  if (service_.memoryBound().exceeded()) {
    metrics.messages_refused_memory.fetch_add(1, std::memory_order_relaxed);
    return reject("resource_exhausted",
                  service_.memoryBound().describe() + "; the message was not acknowledged, resend it later",
                  frame.message->seq(), false);
  }
  if (!takeRateToken()) {
    return reject("rate_limited", "more than the allowed messages per second; resend later", frame.message->seq(), false);
  }
  last_seen_ns_.store(nowNs(), std::memory_order_relaxed);
  handleData(std::move(data), frame.message, received);
}

void RobotSession::handleHello(const v1::Hello& hello) {
  Metrics& metrics = service_.metrics();
  if (principal_.role == Role::kViewer) {
    metrics.messages_rejected.fetch_add(1, std::memory_order_relaxed);
    return sendError("permission_denied", "a viewer token cannot stream robot data", 0, true);
  }
  if (principal_.role == Role::kRobot && principal_.robot_id != hello.robot_id()) {
    metrics.messages_rejected.fetch_add(1, std::memory_order_relaxed);
    return sendError("permission_denied", "this token may only stream as robot '" + principal_.robot_id + "'", 0,
                     true);
  }
  try {
    map_ = service_.openMap(hello.map(), hello.resolution_m());
    robot_id_ = hello.robot_id();
    const uint64_t last_seq = service_.robotConnected(robot_id_, hello.map(), sensorsJson(hello), shared_from_this());
    // The messages this session numbers (seq > last_seq) are scanned with this Hello's lasers.
    service_.declareLasers(robot_id_, hello.map(), last_seq, lasersOf(hello));
    v1::ServerMessage reply;
    v1::Welcome* welcome = reply.mutable_welcome();
    welcome->set_session_id(robot_id_ + "@" + std::to_string(nowNs()));
    welcome->set_robot_id(robot_id_);
    welcome->set_map(hello.map());
    welcome->set_resolution_m(map_->map().resolution());
    welcome->set_last_durable_seq(last_seq);
    welcome->set_max_frame_bytes(service_.config().limits.max_frame_bytes);
    welcome->set_server_version(MappingService::version());
    send(reply);
    spdlog::info("robot {} connected from {} to map {} (last durable seq {})", robot_id_,
                 connection_ ? connection_->peer().address : "?", hello.map(), last_seq);
  } catch (const std::exception& e) {
    robot_id_.clear();
    map_.reset();
    // A store failure (e.g. a full disk) is named by its cause, without the server's paths.
    const auto* store_error = dynamic_cast<const store::StoreError*>(&e);
    spdlog::error("robot {}: session refused: {}", hello.robot_id(), e.what());
    sendError("unavailable", std::string("cannot open the session: ") + (store_error ? store_error->reason() : e.what()),
              0, true);
  }
}

void RobotSession::handleData(std::string frame, std::shared_ptr<v1::RobotMessage> message, Clock::time_point received) {
  const uint64_t seq = message->seq();
  store::MessageRecord record;
  record.map = map_->name();
  record.robot_id = robot_id_;
  record.seq = seq;
  record.kind = static_cast<int32_t>(message->body_case());
  record.received_ns = nowNs();
  record.payload = std::move(frame);

  const size_t limit = service_.config().limits.max_in_flight_per_robot;
  if (in_flight_.fetch_add(1) + 1 >= limit && connection_) {
    paused_ = true;
    connection_->pauseReading(true);
    // Acks may all have come in before paused_ was set; then nobody else resumes.
    if (in_flight_.load() <= limit / 2 && paused_.exchange(false)) connection_->pauseReading(false);
  }
  auto self = shared_from_this();
  auto map = map_;
  const bool queued = service_.committer().submit(
      std::move(record), [self, map, message, seq, received](const store::AppendResult& result, std::exception_ptr error) {
        if (error) {
          std::string text = "unknown";
          std::string reason = "unknown";  // what the robot is told: the cause, not the server's paths
          try {
            std::rethrow_exception(error);
          } catch (const store::StoreError& e) {
            text = e.what();
            reason = e.reason();
          } catch (const std::exception& e) {
            text = e.what();
          }
          self->service_.metrics().store_failures.fetch_add(1, std::memory_order_relaxed);
          spdlog::error("robot {}: message {} not stored: {}", self->robot_id_, seq, text);
          const std::string refusal =
              "the message could not be stored (" + reason + "); it was not acknowledged, resend it later";
          return self->finish(seq, false, received, refusal.c_str());
        }
        if (result.duplicate) {
          // Acked = durable and in the map: the first copy may still be waiting for its worker.
          return self->service_.whenApplied(result.id,
                                            [self, seq, received] { self->finish(seq, true, received, nullptr); });
        }
        self->service_.metrics().messages_durable.fetch_add(1, std::memory_order_relaxed);
        self->service_.apply(*map, result.id, message, self->robot_id_,
                             [self, seq, received] { self->finish(seq, false, received, nullptr); });
      });
  if (!queued) finish(seq, false, received, "the server is overloaded (store queue full); resend later");
}

void RobotSession::finish(uint64_t seq, bool duplicate, Clock::time_point received, const char* error) {
  Metrics& metrics = service_.metrics();
  if (error) {
    metrics.messages_rejected.fetch_add(1, std::memory_order_relaxed);
    sendError("unavailable", error, seq, false);
  } else {
    v1::ServerMessage reply;
    reply.mutable_ack()->set_seq(seq);
    reply.mutable_ack()->set_duplicate(duplicate);
    send(reply);
    metrics.messages_acked.fetch_add(1, std::memory_order_relaxed);
    if (duplicate) metrics.messages_duplicate.fetch_add(1, std::memory_order_relaxed);
    metrics.ack_latency.observe(std::chrono::duration<double>(Clock::now() - received).count());
  }
  const size_t limit = service_.config().limits.max_in_flight_per_robot;
  if (in_flight_.fetch_sub(1) - 1 <= limit / 2 && paused_.exchange(false) && connection_) {
    connection_->pauseReading(false);
  }
}

}  // namespace rmap::app
