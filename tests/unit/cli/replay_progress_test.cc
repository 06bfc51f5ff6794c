#include "cli/replay_progress.h"

#include <gtest/gtest.h>

#include <sstream>

namespace rmap::cli {
namespace {

TEST(ReplayProgress, BarShowsShareRateAndEta) {
  const std::string bar = progressBar({910, 460, 455, 5.0}, 10);
  EXPECT_EQ(bar, "[#####.....]  50.0%  455/910 msgs  91.0 msg/s  ETA 0:05");
  EXPECT_EQ(progressBar({10, 0, 0, 0.0}, 4), "[....]   0.0%  0/10 msgs  0.0 msg/s  ETA --:--");
  EXPECT_EQ(progressBar({10, 10, 10, 2.0}, 4), "[####] 100.0%  10/10 msgs  5.0 msg/s  ETA 0:00");
}

TEST(ReplayProgress, PlainLine) {
  EXPECT_EQ(progressLine({910, 460, 455, 5.0}), "replay: 455/910 messages answered (50%), 91.0 msg/s, ETA 5 s");
  EXPECT_EQ(progressLine({3, 1, 0, 1.0}), "replay: 0/3 messages answered (0%), 0.0 msg/s, ETA unknown");
}

TEST(ReplayProgress, PlainOutputPrintsAtTenthsNotEveryMessage) {
  std::ostringstream out;
  ReplayProgress progress(out, false, 100);
  for (size_t i = 1; i <= 100; ++i) progress.update(i, i);
  progress.finish(100, 100);
  size_t lines = 0;
  for (const char c : out.str()) lines += c == '\n';
  EXPECT_EQ(lines, 12u);  // the first answer, 10 %, 20 %, …, 100 %, and the final line
  EXPECT_EQ(out.str().find('\r'), std::string::npos);
}

TEST(ReplayProgress, TerminalRedrawsInPlace) {
  std::ostringstream out;
  ReplayProgress progress(out, true, 4);
  progress.update(1, 1);
  progress.finish(4, 4);
  EXPECT_EQ(out.str().front(), '\r');
  EXPECT_NE(out.str().find("100.0%"), std::string::npos);
  EXPECT_EQ(out.str().back(), '\n');
}

}  // namespace
}  // namespace rmap::cli
