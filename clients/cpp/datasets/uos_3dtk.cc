#include "datasets/uos_3dtk.h"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <numbers>
#include <stdexcept>

#include "datasets/compressed_file.h"
#include "datasets/text_fields.h"

// How the conventions were checked on the 3DTK example data (three scans of
// one room, the scanner moving ≈1.6 m forward each time): on a subsample,
// the median nearest-neighbour distance from scan 1 to scan 0 (and 2 to 1)
// is 2.9 (3.1) cm with the .frames poses, 3.1 (3.3) cm with the .pose poses
// under Rx·Ry·Rz, 4.8 (7.2) cm with the inverse rotations, 6.1 (4.5) cm with
// no poses and 110 (128) cm with the translations negated. The scanner looks
// forward: every point of scan 0 has x ≥ 0 here. uos_3dtk_test.cc keeps the
// overlap check.

namespace rmap::datasets {
namespace {

namespace fs = std::filesystem;

/// 3DTK's `W x H` header line (uosHeaderTest): digits, " x ", digits.
bool isDimensionHeader(std::string_view line) {
  const size_t x = line.find(" x ");
  auto digits = [](std::string_view s) {
    return !s.empty() && s.find_first_not_of("0123456789") == std::string_view::npos;
  };
  return x != std::string_view::npos && digits(line.substr(0, x)) && digits(line.substr(x + 3));
}

/// Rejects matrices that are not rotations plus translation, e.g. a row-major file.
void checkRigid(const Eigen::Matrix4d& m, const std::string& source, size_t line) {
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  if ((m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6 ||
      (r * r.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3 || r.determinant() < 0) {
    throwAt(source, line, "matrix is not a rigid transform (expected column-major 4x4 with last row 0 0 0 1)");
  }
}

/// Last pose of a .frames file; false when the file has no pose lines.
bool readFramesPose(const std::string& path, Eigen::Matrix4d& pose) {
  const std::string text = readFileMaybeCompressed(path);
  TextLines lines(text);
  std::string_view line;
  std::string_view fields[18];
  bool found = false;
  while (lines.next(line)) {
    const size_t n = splitFields(stripComment(line), fields, std::size(fields));
    if (n == 0) continue;
    if (n != 17) {
      throwAt(path, lines.number(), "expected 16 matrix values and a type code, got " + std::to_string(n) + " fields");
    }
    for (int i = 0; i < 16; ++i) {
      const double v = parseNumber(fields[i], path, lines.number());
      if (!std::isfinite(v)) throwAt(path, lines.number(), "non-finite matrix value");
      pose(i % 4, i / 4) = v;  // column-major
    }
    parseNumber(fields[16], path, lines.number());
    checkRigid(pose, path, lines.number());
    found = true;
  }
  return found;
}

Eigen::Matrix4d readUosPose(const std::string& path) {
  const std::string text = readFileMaybeCompressed(path);
  TextLines lines(text);
  std::string_view line;
  std::string_view fields[4];
  double v[6];
  int read = 0;
  while (read < 6 && lines.next(line)) {
    const size_t n = splitFields(stripComment(line), fields, std::size(fields));
    if (n == 0) continue;
    if (n != 3) throwAt(path, lines.number(), "expected 3 numbers, got " + std::to_string(n) + " fields");
    for (size_t i = 0; i < 3; ++i) {
      v[read] = parseNumber(fields[i], path, lines.number());
      if (!std::isfinite(v[read])) throwAt(path, lines.number(), "non-finite pose value");
      ++read;
    }
  }
  if (read < 6) throw std::runtime_error(path + ": expected a translation line and a rotation line");
  constexpr double kDegToRad = std::numbers::pi / 180.0;
  Eigen::Affine3d pose = Eigen::Translation3d(v[0], v[1], v[2]) *
                         Eigen::AngleAxisd(v[3] * kDegToRad, Eigen::Vector3d::UnitX()) *
                         Eigen::AngleAxisd(v[4] * kDegToRad, Eigen::Vector3d::UnitY()) *
                         Eigen::AngleAxisd(v[5] * kDegToRad, Eigen::Vector3d::UnitZ());
  return pose.matrix();
}

/// Left-handed uos centimetres (x right, y up, z forward) to right-handed
/// metres (x forward, y left, z up).
Eigen::Vector3f toRightHandedMetres(const Eigen::Vector3d& p) {
  return Eigen::Vector3f(static_cast<float>(p.z() / 100.0), static_cast<float>(-p.x() / 100.0),
                         static_cast<float>(p.y() / 100.0));
}

PointScan readScan(const std::string& points_path, const Eigen::Matrix4d& pose, UosReadStats& stats) {
  const std::string text = readFileMaybeCompressed(points_path);
  PointScan scan;
  scan.sensor_origin_m = toRightHandedMetres(pose.topRightCorner<3, 1>());
  const Eigen::Matrix3d r = pose.topLeftCorner<3, 3>();
  const Eigen::Vector3d t = pose.topRightCorner<3, 1>();
  TextLines lines(text);
  std::string_view line;
  std::string_view fields[4];
  while (lines.next(line)) {
    if (lines.number() == 1 && isDimensionHeader(line)) continue;
    const size_t n = splitFields(stripComment(line), fields, std::size(fields));
    if (n == 0) continue;
    if (n != 3) throwAt(points_path, lines.number(), "expected 3 numbers x y z, got " + std::to_string(n) + " fields");
    const Eigen::Vector3d p(parseNumber(fields[0], points_path, lines.number()),
                            parseNumber(fields[1], points_path, lines.number()),
                            parseNumber(fields[2], points_path, lines.number()));
    ++stats.points_read;
    if (!p.allFinite()) {
      ++stats.dropped_non_finite;
      continue;
    }
    const double range = p.norm();
    if (range < kUosMinRangeCm) {
      ++stats.dropped_near;
      continue;
    }
    if (range >= kUosMaxRangeCm) {
      ++stats.dropped_far;
      continue;
    }
    scan.points_m.push_back(toRightHandedMetres(r * p + t));
  }
  return scan;
}

std::string scanName(const std::string& dir, size_t index, const char* suffix) {
  char name[32];
  std::snprintf(name, sizeof name, "scan%03zu%s", index, suffix);
  return (fs::path(dir) / name).string();
}

}  // namespace

std::vector<PointScan> readUos3dtk(const std::string& dir, UosReadStats* stats) {
  UosReadStats local;
  UosReadStats& s = stats ? *stats : local;
  s = {};
  if (!fs::exists(scanName(dir, 0, ".3d"))) {
    throw std::runtime_error(dir + ": no scan000.3d (not a 3DTK uos folder)");
  }
  std::vector<PointScan> scans;
  for (size_t i = 0; fs::exists(scanName(dir, i, ".3d")); ++i) {
    const std::string frames = scanName(dir, i, ".frames");
    const std::string pose_file = scanName(dir, i, ".pose");
    Eigen::Matrix4d pose;
    if (fs::exists(frames) && readFramesPose(frames, pose)) {
      ++s.poses_from_frames;
    } else if (fs::exists(pose_file)) {
      pose = readUosPose(pose_file);
    } else {
      throw std::runtime_error(scanName(dir, i, ".3d") + ": neither .frames nor .pose beside it");
    }
    scans.push_back(readScan(scanName(dir, i, ".3d"), pose, s));
  }
  return scans;
}

}  // namespace rmap::datasets

