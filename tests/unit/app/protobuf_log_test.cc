#include "app/protobuf_log.h"

#include <google/protobuf/stubs/logging.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <memory>
#include <sstream>

#include "app/ingest.h"

namespace rmap::app {
namespace {

// A frame whose Hello robot_id is not UTF-8: libprotobuf refuses it and logs why.
std::string helloWithInvalidUtf8() {
  v1::RobotMessage m;
  m.mutable_hello()->set_robot_id("bot");
  std::string frame = m.SerializeAsString();
  frame.back() = '\xFF';
  return frame;
}

TEST(ProtobufLog, ParseErrorsOfPeerBytesGoToTheDebugLevel) {
  std::ostringstream out;
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(out);
  const auto previous = spdlog::default_logger();
  spdlog::set_default_logger(std::make_shared<spdlog::logger>("test", sink));

  google::protobuf::LogHandler* const before = google::protobuf::SetLogHandler(nullptr);
  routeProtobufLogToSpdlog();
  spdlog::set_level(spdlog::level::info);
  EXPECT_EQ(decodeRobotFrame(helloWithInvalidUtf8(), true, nullptr, LimitsConfig{}).code, "invalid_message");
  EXPECT_EQ(out.str(), "");  // nothing at info: a robot cannot fill the log with bad frames

  spdlog::set_level(spdlog::level::debug);
  decodeRobotFrame(helloWithInvalidUtf8(), true, nullptr, LimitsConfig{});
  EXPECT_NE(out.str().find("invalid UTF-8"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("[debug]"), std::string::npos) << out.str();

  google::protobuf::SetLogHandler(before);
  spdlog::set_default_logger(previous);
}

}  // namespace
}  // namespace rmap::app
