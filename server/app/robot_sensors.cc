#include "app/robot_sensors.h"

#include <Eigen/Geometry>
#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "app/ingest.h"

namespace rmap::app {

std::vector<Laser2dSetup> lasersOf(const v1::Hello& hello) {
  std::vector<Laser2dSetup> lasers;
  for (const v1::SensorDescription& s : hello.sensors()) {
    if (s.kind() != v1::SensorDescription::LASER_2D) continue;
    const Eigen::Isometry3d mount = toIsometry(s.mount());
    const Eigen::Vector3d x_axis = mount.linear().col(0);
    lasers.push_back({s.name(), s.model(), mount.translation().x(), mount.translation().y(),
                      mount.translation().z(), std::atan2(x_axis.y(), x_axis.x())});
  }
  return lasers;
}

std::string lasersJson(const std::string& robot_id, uint64_t after_seq, const std::vector<Laser2dSetup>& lasers) {
  nlohmann::json list = nlohmann::json::array();
  for (const Laser2dSetup& l : lasers) {
    list.push_back({{"name", l.name}, {"model", l.model}, {"x_m", l.x_m}, {"y_m", l.y_m}, {"z_m", l.z_m},
                    {"yaw_rad", l.yaw_rad}});
  }
  return nlohmann::json{{"robot_id", robot_id}, {"after_seq", after_seq}, {"lasers", std::move(list)}}.dump();
}

const RobotSensors::Entry* RobotSensors::entryFor(const std::string& robot_id, uint64_t seq) const {
  const auto it = entries_.find(robot_id);
  if (it == entries_.end()) return nullptr;
  // The latest Hello that numbered this seq; Hellos of later sessions start above it.
  for (auto e = it->second.rbegin(); e != it->second.rend(); ++e) {
    if (e->after_seq < seq) return &*e;
  }
  return nullptr;
}

bool RobotSensors::isNew(const std::string& robot_id, uint64_t after_seq,
                         const std::vector<Laser2dSetup>& lasers) const {
  std::lock_guard lock(mutex_);
  const Entry* current = entryFor(robot_id, after_seq + 1);
  return current ? current->lasers != lasers : !lasers.empty();
}

void RobotSensors::add(const std::string& robot_id, uint64_t after_seq, std::vector<Laser2dSetup> lasers) {
  std::lock_guard lock(mutex_);
  entries_[robot_id].push_back({after_seq, std::move(lasers)});
}

void RobotSensors::addJson(const std::string& json) {
  try {
    const nlohmann::json in = nlohmann::json::parse(json);
    std::vector<Laser2dSetup> lasers;
    for (const nlohmann::json& l : in.at("lasers")) {
      lasers.push_back({l.at("name").get<std::string>(), l.at("model").get<std::string>(), l.at("x_m").get<double>(),
                        l.at("y_m").get<double>(), l.at("z_m").get<double>(), l.at("yaw_rad").get<double>()});
    }
    std::lock_guard lock(mutex_);
    entries_[in.at("robot_id").get<std::string>()].push_back({in.at("after_seq").get<uint64_t>(), std::move(lasers)});
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(std::string("stored robot sensors are unreadable: ") + e.what());
  }
}

std::optional<Laser2dSetup> RobotSensors::laser(const std::string& robot_id, uint64_t seq,
                                                const std::string& sensor) const {
  std::lock_guard lock(mutex_);
  const Entry* entry = entryFor(robot_id, seq);
  if (!entry) return std::nullopt;
  for (const Laser2dSetup& l : entry->lasers) {
    if (l.name == sensor) return l;
  }
  if (entry->lasers.size() == 1) return entry->lasers.front();
  return std::nullopt;
}

}  // namespace rmap::app
