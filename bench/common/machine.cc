#include "common/machine.h"

#include <fstream>
#include <thread>

namespace rmap::bench {

std::string cpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  }
  return "unknown";
}

nlohmann::json machineJson() {
  return {{"cpu", cpuModel()}, {"hardware_threads", std::thread::hardware_concurrency()}};
}

}  // namespace rmap::bench
