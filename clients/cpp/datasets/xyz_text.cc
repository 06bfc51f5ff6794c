#include "datasets/xyz_text.h"

#include <Eigen/Geometry>
#include <cmath>
#include <iterator>

#include "datasets/compressed_file.h"
#include "datasets/text_fields.h"

namespace rmap::datasets {

std::vector<PointScan> parseXyzText(std::string_view text, const std::string& source) {
  std::vector<PointScan> scans(1);  // the implicit scan at the origin
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  TextLines lines(text);
  std::string_view line;
  std::string_view fields[8];
  double v[6];
  while (lines.next(line)) {
    const size_t n = splitFields(stripComment(line), fields, std::size(fields));
    if (n == 0) continue;
    const bool node = fields[0] == "NODE";
    const size_t first = node ? 1 : 0;  // index of the first number
    const size_t count = node ? 6 : 3;
    if (n != first + count) {
      throwAt(source, lines.number(),
              node ? "NODE needs x y z roll pitch yaw, got " + std::to_string(n - 1) + " values"
                   : "expected 3 numbers x y z, got " + std::to_string(n) + " fields");
    }
    for (size_t i = 0; i < count; ++i) {
      v[i] = parseNumber(fields[first + i], source, lines.number());
      if (!std::isfinite(v[i])) {
        throwAt(source, lines.number(), "non-finite value \"" + std::string(fields[first + i]) + "\"");
      }
    }
    if (node) {
      pose = Eigen::Translation3d(v[0], v[1], v[2]) * Eigen::AngleAxisd(v[5], Eigen::Vector3d::UnitZ()) *
             Eigen::AngleAxisd(v[4], Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(v[3], Eigen::Vector3d::UnitX());
      scans.push_back({pose.translation().cast<float>(), {}});
    } else {
      scans.back().points_m.push_back((pose * Eigen::Vector3d(v[0], v[1], v[2])).cast<float>());
    }
  }
  if (scans.front().points_m.empty()) scans.erase(scans.begin());
  return scans;
}

std::vector<PointScan> readXyzText(const std::string& path) {
  return parseXyzText(readFileMaybeCompressed(path), path);
}

}  // namespace rmap::datasets
