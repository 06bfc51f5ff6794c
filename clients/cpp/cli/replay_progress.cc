#include "cli/replay_progress.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace rmap::cli {
namespace {

/// ANSI "erase to the end of the line": a shorter redraw leaves nothing of the longer one behind.
constexpr const char* kClearToEnd = "\033[K";

double fraction(const ReplayProgressState& s) {
  return s.total ? static_cast<double>(s.acked) / static_cast<double>(s.total) : 1.0;
}

double rate(const ReplayProgressState& s) { return s.elapsed_s > 0.0 ? static_cast<double>(s.acked) / s.elapsed_s : 0.0; }

/// Seconds left at the current rate, < 0 when unknown.
double etaSeconds(const ReplayProgressState& s) {
  const double r = rate(s);
  if (r <= 0.0) return -1.0;
  return static_cast<double>(s.total - std::min(s.acked, s.total)) / r;
}

}  // namespace

std::string progressBar(const ReplayProgressState& s, int bar_width) {
  const double f = std::clamp(fraction(s), 0.0, 1.0);
  const int filled = static_cast<int>(std::floor(f * bar_width));
  std::string bar(static_cast<size_t>(bar_width) + 2, '.');
  bar.front() = '[';
  bar.back() = ']';
  std::fill_n(bar.begin() + 1, filled, '#');
  char eta[32];
  const double e = etaSeconds(s);
  if (e < 0.0) {
    std::snprintf(eta, sizeof eta, "ETA --:--");
  } else {
    const long t = std::lround(e);
    std::snprintf(eta, sizeof eta, "ETA %ld:%02ld", t / 60, t % 60);
  }
  char text[160];
  std::snprintf(text, sizeof text, " %5.1f%%  %zu/%zu msgs  %.1f msg/s  %s", 100.0 * f, s.acked, s.total, rate(s), eta);
  return bar + text;
}

std::string progressLine(const ReplayProgressState& s) {
  char text[160];
  const double e = etaSeconds(s);
  std::snprintf(text, sizeof text, "replay: %zu/%zu messages answered (%.0f%%), %.1f msg/s, ETA %s", s.acked, s.total,
                100.0 * fraction(s), rate(s), e < 0.0 ? "unknown" : (std::to_string(std::lround(e)) + " s").c_str());
  return text;
}

ReplayProgress::ReplayProgress(std::ostream& out, bool terminal, size_t total)
    : out_(out), terminal_(terminal), total_(total) {}

ReplayProgressState ReplayProgress::state(size_t sent, size_t acked) const {
  return {total_, sent, acked, std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count()};
}

void ReplayProgress::update(size_t sent, size_t acked) {
  const auto now = std::chrono::steady_clock::now();
  if (terminal_) {
    if (now - last_draw_ < std::chrono::milliseconds(100)) return;
    last_draw_ = now;
    out_ << "\r" << progressBar(state(sent, acked)) << kClearToEnd << std::flush;
    return;
  }
  const size_t tenth = total_ ? acked * 10 / total_ : 10;
  if (tenth <= last_tenth_ && now - last_draw_ < std::chrono::seconds(5)) return;
  last_tenth_ = std::max(last_tenth_, tenth);
  last_draw_ = now;
  out_ << progressLine(state(sent, acked)) << "\n" << std::flush;
}

void ReplayProgress::finish(size_t sent, size_t acked) {
  if (terminal_) {
    out_ << "\r" << progressBar(state(sent, acked)) << kClearToEnd << "\n" << std::flush;
  } else {
    out_ << progressLine(state(sent, acked)) << "\n" << std::flush;
  }
}

}  // namespace rmap::cli
