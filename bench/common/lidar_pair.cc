#include "common/lidar_pair.h"

#include <fstream>
#include <stdexcept>

namespace rmap::bench {

Eigen::Matrix4d readTransform(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  Eigen::Matrix4d t;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      if (!(in >> t(r, c))) throw std::runtime_error(path + ": expected 16 numbers (4×4 row-major)");
    }
  }
  return t;
}

const std::vector<float>& intensityOf(const datasets::PlyCloud& cloud, const std::string& path) {
  for (const auto& [name, values] : cloud.scalars) {
    if (name.find("intensity") != std::string::npos || name.find("reflectivity") != std::string::npos) return values;
  }
  throw std::runtime_error(path + ": no vertex property named like 'intensity' or 'reflectivity'");
}

}  // namespace rmap::bench
