#pragma once
/// @file protobuf_log.h
/// Where libprotobuf's own messages go in rmapd. Parsing a peer's bytes makes
/// it write an ERROR line to stderr per rejected string field (invalid UTF-8)
/// or oversized message, so a robot sending such frames would add a line to
/// the server's log per frame (found by tests/fuzz/robot_message_fuzz.cc).
/// The peer is answered already (Error invalid_message, 400), so these go to
/// the debug level.

namespace rmap::app {

/// Sends libprotobuf's log through spdlog: its ERROR and lower at debug, FATAL at critical.
void routeProtobufLogToSpdlog();

}  // namespace rmap::app
