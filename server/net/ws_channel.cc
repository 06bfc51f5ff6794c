#include "net/ws_channel.h"

#include <boost/asio/post.hpp>
#include <utility>

namespace rmap::net {

namespace {
/// RFC 6455 §5.5: control frame payload ≤ 125 bytes, 2 of them the code.
constexpr size_t kMaxCloseReasonBytes = 123;
}  // namespace

WsChannel::WsChannel(Peer peer, size_t max_queue_bytes, std::shared_ptr<WsDriver> driver,
                     boost::asio::any_io_executor strand)
    : peer_(std::move(peer)),
      max_queue_bytes_(max_queue_bytes),
      driver_(std::move(driver)),
      strand_(std::move(strand)) {}

bool WsChannel::send(std::string data, bool binary) {
  std::lock_guard lock(mutex_);
  if (!driver_ || close_) return false;
  if (data.size() > max_queue_bytes_ - queued_bytes_) return false;
  queued_bytes_ += data.size();
  queue_.push_back(Frame{std::move(data), binary});
  if (!flush_scheduled_) {
    flush_scheduled_ = true;
    post(&WsDriver::flushQueue);
  }
  return true;
}

size_t WsChannel::queuedBytes() const {
  std::lock_guard lock(mutex_);
  return queued_bytes_;
}

void WsChannel::pauseReading(bool paused) {
  paused_.store(paused, std::memory_order_release);
  if (paused) return;  // the read loop checks the flag before each read
  std::lock_guard lock(mutex_);
  if (driver_) post(&WsDriver::resumeReading);
}

void WsChannel::close(uint16_t code, const std::string& reason) {
  std::lock_guard lock(mutex_);
  if (!driver_ || close_) return;
  close_ = CloseRequest{code, reason.substr(0, kMaxCloseReasonBytes)};
  if (!flush_scheduled_) {
    flush_scheduled_ = true;
    post(&WsDriver::flushQueue);
  }
}

WsChannel::Next WsChannel::next(Frame& frame, CloseRequest& close) {
  std::lock_guard lock(mutex_);
  if (!queue_.empty()) {
    frame = std::move(queue_.front());
    queue_.pop_front();
    return Next::kFrame;
  }
  if (close_ && !close_taken_) {
    close_taken_ = true;
    close = *close_;
    return Next::kClose;
  }
  flush_scheduled_ = false;
  return Next::kIdle;
}

void WsChannel::written(size_t bytes) {
  std::lock_guard lock(mutex_);
  if (driver_) queued_bytes_ -= bytes;  // detach() already dropped the count
}

void WsChannel::detach() {
  std::shared_ptr<WsDriver> driver;
  boost::asio::any_io_executor strand;
  std::deque<Frame> dropped;
  {
    std::lock_guard lock(mutex_);
    driver = std::move(driver_);
    strand = std::move(strand_);
    strand_ = {};
    dropped.swap(queue_);
    queued_bytes_ = 0;
  }
  // Released outside the lock: dropping the driver may destroy the session.
}

void WsChannel::post(void (WsDriver::*step)()) {
  boost::asio::post(strand_, [driver = driver_, step] { ((*driver).*step)(); });
}

}  // namespace rmap::net
