#pragma once
/// @file viewer_load.h
/// Many subscribers of rmapd's viewer stream (/v1/stream/viewer) at once, for
/// load tests and benchmarks. Reading viewers take every frame as it comes
/// and count them by type; stalled viewers complete the handshake and never
/// read again (a frozen browser tab), with a small socket receive buffer so
/// that what piles up for them piles up in the server. Plain ws:// only.

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace rmap::client {

struct ViewerLoadOptions {
  std::string server_url = "ws://127.0.0.1:8080";  ///< ws://host:port (or http://, same port)
  std::string token;                               ///< Authorization: Bearer when set
  std::string map;                                 ///< the stream's `map`; "" = every map
  int reading = 1;
  int stalled = 0;
  int stalled_receive_buffer_bytes = 4096;  ///< SO_RCVBUF of a stalled viewer's socket
  std::chrono::milliseconds timeout{10000}; ///< per connection and handshake
};

/// What one reading viewer received.
struct ViewerCounts {
  uint64_t frames = 0;
  uint64_t bytes = 0;
  uint64_t tiles = 0;    ///< frames of type "tiles"
  uint64_t poses = 0;    ///< frames of type "poses"
  uint64_t resyncs = 0;  ///< frames of type "resync"
};

struct ViewerLoadResult {
  std::vector<ViewerCounts> reading;  ///< one per reading viewer
  std::vector<std::string> errors;    ///< streams that ended before stop()
};

class ViewerLoad {
 public:
  /// Connects every viewer (reading ones first) and starts reading.
  /// @throws ClientError when a connection or handshake fails, naming the viewer
  explicit ViewerLoad(const ViewerLoadOptions& options);
  ~ViewerLoad();  ///< stops
  ViewerLoad(const ViewerLoad&) = delete;
  ViewerLoad& operator=(const ViewerLoad&) = delete;

  /// Closes every viewer and returns what the reading ones received. Once only.
  ViewerLoadResult stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rmap::client
