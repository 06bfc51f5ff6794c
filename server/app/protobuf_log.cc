#include "app/protobuf_log.h"

#include <google/protobuf/stubs/logging.h>
#include <spdlog/spdlog.h>

#include <string>

namespace rmap::app {

void routeProtobufLogToSpdlog() {
  google::protobuf::SetLogHandler(
      [](google::protobuf::LogLevel level, const char* file, int line, const std::string& message) {
        // FATAL aborts the process right after: the one that must reach the log.
        const spdlog::level::level_enum to =
            level == google::protobuf::LOGLEVEL_FATAL ? spdlog::level::critical : spdlog::level::debug;
        spdlog::log(to, "libprotobuf {}:{}: {}", file, line, message);
      });
}

}  // namespace rmap::app
