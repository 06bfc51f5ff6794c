// Fuzz target: a robot stream frame as rmapd receives it (RobotSession::onMessage):
// decodeRobotFrame as the stream's first frame (a Hello) and as a data frame for
// a map, then the conversion an accepted cloud takes into the map frame.
#include <google/protobuf/stubs/logging.h>

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "app/ingest.h"

namespace {

using rmap::app::RobotFrame;

void decodeAsData(std::string_view frame, double resolution_m) {
  const rmap::map3d::Grid grid(resolution_m);
  const RobotFrame data = rmap::app::decodeRobotFrame(frame, true, &grid, rmap::app::LimitsConfig{});
  if (data.message && data.message->has_cloud()) {
    const rmap::app::CloudInMap in_map = rmap::app::cloudInMap(data.message->cloud());
    // A checked cloud has whole points and a sensor origin inside the grid.
    rmap::map3d::CellKey origin;
    if (in_map.points_m.size() * 3 != static_cast<size_t>(data.message->cloud().xyz_m_size()) ||
        !grid.cellChecked(rmap::app::sensorOrigin(data.message->cloud()), origin)) {
      __builtin_trap();
    }
  }
}

}  // namespace

// libprotobuf logs each refused string field; rmapd sends these to its debug log
// (app/protobuf_log.h), here they would only slow the run down.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  google::protobuf::SetLogHandler(nullptr);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size) {
  const std::string_view frame(reinterpret_cast<const char*>(bytes), size);
  const RobotFrame hello = rmap::app::decodeRobotFrame(frame, true, nullptr, rmap::app::LimitsConfig{});
  if (hello.message && !hello.message->has_hello()) __builtin_trap();
  // The server default and the finest resolution a Hello may ask for.
  decodeAsData(frame, 0.1);
  decodeAsData(frame, rmap::app::kMinResolution_m);
  return 0;
}
