#pragma once
/// @file replay_progress.h
/// The progress of `rmap replay` on stderr: a bar redrawn in place on a
/// terminal, plain lines (every 10 % or 5 s) otherwise, so logs stay readable.

#include <chrono>
#include <cstddef>
#include <ostream>
#include <string>

namespace rmap::cli {

struct ReplayProgressState {
  size_t total = 0;     ///< messages to send
  size_t sent = 0;
  size_t acked = 0;     ///< answered: acknowledged or refused
  double elapsed_s = 0.0;
};

/// "[##########..........]  50.0%  455/910 msgs  91.0 msg/s  ETA 0:05"
/// (rate and ETA from answered messages; "ETA --:--" before the first).
std::string progressBar(const ReplayProgressState& state, int bar_width = 30);

/// "replay: 455/910 messages answered (50%), 91.0 msg/s, ETA 5 s"
std::string progressLine(const ReplayProgressState& state);

class ReplayProgress {
 public:
  /// @param terminal  redraw one line in place (a TTY) rather than print lines
  ReplayProgress(std::ostream& out, bool terminal, size_t total);
  /// Draws when due: at most every 100 ms on a terminal, every 10 % or 5 s otherwise.
  void update(size_t sent, size_t acked);
  /// Draws the final state and ends the line.
  void finish(size_t sent, size_t acked);

 private:
  ReplayProgressState state(size_t sent, size_t acked) const;

  std::ostream& out_;
  bool terminal_;
  size_t total_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_draw_{};
  size_t last_tenth_ = 0;
};

}  // namespace rmap::cli
