#pragma once
/// @file machine.h
/// What the benchmark ran on, for the JSON every benchmark writes.

#include <nlohmann/json.hpp>
#include <string>

namespace rmap::bench {

/// The CPU model from /proc/cpuinfo ("unknown" elsewhere).
std::string cpuModel();
/// {"cpu", "hardware_threads"}
nlohmann::json machineJson();

}  // namespace rmap::bench
