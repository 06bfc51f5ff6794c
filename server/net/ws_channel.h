#pragma once
/// @file ws_channel.h
/// Private to the net layer: the WsConnection handed to handlers. It is the
/// thread-safe half of a WebSocket session: a byte-bounded outbox plus the
/// pause and close switches. Handlers fill it from any thread; the session
/// drains it on its strand, one frame at a time.

#include <boost/asio/any_io_executor.hpp>
#include <atomic>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "net/service.h"

namespace rmap::net {

/// The session side the channel wakes up; both run on the session's strand.
class WsDriver {
 public:
  virtual ~WsDriver() = default;
  /// Writes the queued frames, then a requested close, one at a time.
  virtual void flushQueue() = 0;
  /// Restarts the read loop after pauseReading(false).
  virtual void resumeReading() = 0;
};

class WsChannel final : public WsConnection {
 public:
  struct Frame {
    std::string data;
    bool binary = false;
  };
  struct CloseRequest {
    uint16_t code = 1000;
    std::string reason;
  };
  /// The writer's next step (see next()).
  enum class Next { kFrame, kClose, kIdle };

  /// @param driver kept alive until detach(): a session whose reading is
  ///        paused has no I/O pending, and only this reference keeps it
  /// @param strand the session's strand, where the driver is called
  WsChannel(Peer peer, size_t max_queue_bytes, std::shared_ptr<WsDriver> driver, boost::asio::any_io_executor strand);

  bool send(std::string data, bool binary) override;
  size_t queuedBytes() const override;
  void pauseReading(bool paused) override;
  /// `reason` is cut to the 123 bytes a close frame can carry.
  void close(uint16_t code, const std::string& reason) override;
  const Peer& peer() const override { return peer_; }

  // The session's side, on its strand.

  /// Takes the next frame to write (kFrame), or the close to send once the
  /// queue is empty (kClose); kIdle means nothing to do until the next
  /// send() or close(), which will call flushQueue() again.
  Next next(Frame& frame, CloseRequest& close);
  /// A frame of `bytes` taken by next() reached the socket.
  void written(size_t bytes);
  bool paused() const { return paused_.load(std::memory_order_acquire); }
  /// The connection ended: later sends fail, the queue is dropped and the
  /// driver released.
  void detach();

 private:
  /// Schedules `step` on the strand; needs mutex_ held and a driver.
  void post(void (WsDriver::*step)());

  const Peer peer_;
  const size_t max_queue_bytes_;
  std::atomic<bool> paused_{false};
  mutable std::mutex mutex_;
  std::shared_ptr<WsDriver> driver_;  ///< null once detached
  /// Copy of the session's strand, dropped on detach: it must not outlive the
  /// io_context, while the channel may (handlers keep it).
  boost::asio::any_io_executor strand_;
  std::deque<Frame> queue_;
  size_t queued_bytes_ = 0;  ///< queue_ plus the frame being written
  bool flush_scheduled_ = false;  ///< flushQueue() posted or the writer busy
  std::optional<CloseRequest> close_;
  bool close_taken_ = false;
};

}  // namespace rmap::net
