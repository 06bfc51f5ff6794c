#include "cli/replay_run.h"

#include <gtest/gtest.h>

namespace rmap::cli {
namespace {

ReplaySummary complete(size_t frames) {
  ReplaySummary s;
  s.format = "xyz";
  s.frames = s.sent = s.acked = frames;
  return s;
}

TEST(ReplayRun, OkOnlyWhenEveryFrameWasAcknowledged) {
  EXPECT_TRUE(complete(3).ok());
  ReplaySummary refused = complete(3);
  refused.acked = 2;
  refused.errors = 1;
  EXPECT_FALSE(refused.ok());
  ReplaySummary stopped = complete(3);
  stopped.sent = stopped.acked = 1;
  stopped.failure = "b.bin: 17 bytes is not a whole number of 16-byte records";
  EXPECT_FALSE(stopped.ok());
  EXPECT_NE(stopped.text().find("replay FAILED"), std::string::npos);
  EXPECT_NE(stopped.text().find("failure: b.bin: 17 bytes"), std::string::npos);
  const nlohmann::json j = stopped.toJson();
  EXPECT_EQ(j["ok"], false);
  EXPECT_EQ(j["messages_sent"], 1);
  EXPECT_EQ(j["failure"], stopped.failure);
  EXPECT_TRUE(complete(1).toJson()["failure"].is_null());
}

TEST(ReplayRun, ResumedRobotIsNoted) {
  ReplaySummary s = complete(2);
  s.robot_id = "bot";
  s.resumed_after_seq = 910;
  EXPECT_NE(s.text().find("robot bot had 910 messages in the server already"), std::string::npos) << s.text();
}

TEST(ReplayRun, UnreachableServerIsAFailureNotAThrow) {
  ReplaySource source;
  source.format = ReplayFormat::kXyzText;
  source.frames = 1;
  source.frame = [](size_t) {
    ADD_FAILURE() << "no frame is read before the connection is up";
    return ReplayFrame{};
  };
  // Nothing listens on port 1.
  ReplayOptions options;
  options.server_url = "ws://127.0.0.1:1";
  options.map = "m";
  options.robot_id = "r";
  options.timeout = std::chrono::milliseconds(2000);
  const ReplaySummary s = runReplay(source, options, nullptr);
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(s.sent, 0u);
  EXPECT_NE(s.failure.find("connecting to ws://127.0.0.1:1"), std::string::npos) << s.failure;
}

}  // namespace
}  // namespace rmap::cli
