#include "datasets/octomap_graph.h"

#include <cmath>
#include <cstring>
#include <set>
#include <stdexcept>

#include "datasets/compressed_file.h"

namespace rmap::datasets {
namespace {

/// Reads the little-endian values of the file in order, naming the offset of what is wrong.
class ByteReader {
 public:
  ByteReader(std::string_view bytes, const std::string& source) : bytes_(bytes), source_(source) {}

  template <class T>
  T get(const char* what) {
    if (bytes_.size() - pos_ < sizeof(T)) fail(std::string("truncated: ") + what + " is missing");
    T v;
    std::memcpy(&v, bytes_.data() + pos_, sizeof v);
    pos_ += sizeof v;
    return v;
  }

  double finite(const char* what) {
    const size_t at = pos_;
    const double v = get<double>(what);
    if (!std::isfinite(v)) failAt(at, std::string(what) + " is not finite");
    return v;
  }

  /// An octomath vector: an i32 size tag that must be `n`, then n doubles.
  void vector(int32_t n, double* out, const char* what) {
    const size_t at = pos_;
    const int32_t tag = get<int32_t>(what);
    if (tag != n) failAt(at, std::string(what) + " has size tag " + std::to_string(tag) + ", expected " + std::to_string(n));
    for (int32_t i = 0; i < n; ++i) out[i] = finite(what);
  }

  Eigen::Isometry3d pose(const char* what) {
    double t[3], q[4];
    vector(3, t, what);
    const size_t at = pos_;
    vector(4, q, what);
    const Eigen::Quaterniond rotation(q[0], q[1], q[2], q[3]);
    if (!(rotation.norm() > 1e-9)) failAt(at, std::string(what) + " has a zero quaternion");
    Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
    out.linear() = rotation.normalized().toRotationMatrix();
    out.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
    return out;
  }

  size_t offset() const { return pos_; }
  size_t left() const { return bytes_.size() - pos_; }
  [[noreturn]] void fail(const std::string& problem) const { failAt(pos_, problem); }
  [[noreturn]] void failAt(size_t at, const std::string& problem) const {
    throw std::runtime_error(source_ + ": offset " + std::to_string(at) + ": " + problem);
  }

 private:
  std::string_view bytes_;
  const std::string& source_;
  size_t pos_ = 0;
};

constexpr size_t kPointBytes = 4 + 3 * 8;

}  // namespace

std::vector<GraphScan> parseOctomapGraph(std::string_view bytes, const std::string& source) {
  ByteReader in(bytes, source);
  const uint32_t nodes = in.get<uint32_t>("node count");
  std::vector<GraphScan> scans;
  std::set<uint32_t> ids;
  for (uint32_t k = 0; k < nodes; ++k) {
    GraphScan scan;
    const uint32_t points = in.get<uint32_t>("point count");
    // Checked before reserving, so a garbled count cannot ask for gigabytes.
    if (in.left() / kPointBytes < points) {
      in.fail("truncated: node " + std::to_string(k) + " claims " + std::to_string(points) + " points");
    }
    scan.points_m.reserve(points);
    for (uint32_t i = 0; i < points; ++i) {
      double p[3];
      in.vector(3, p, "point");
      scan.points_m.emplace_back(static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2]));
    }
    scan.sensor_pose = in.pose("node pose");
    scan.id = in.get<uint32_t>("node id");
    ids.insert(scan.id);
    scans.push_back(std::move(scan));
  }
  const uint32_t edges = in.get<uint32_t>("edge count");
  for (uint32_t e = 0; e < edges; ++e) {
    for (const char* end : {"edge first id", "edge second id"}) {
      const size_t at = in.offset();
      const uint32_t id = in.get<uint32_t>(end);
      if (!ids.contains(id)) in.failAt(at, std::string(end) + " " + std::to_string(id) + " names no node");
    }
    in.pose("edge constraint");
    in.finite("edge weight");
  }
  if (in.left() != 0) in.fail(std::to_string(in.left()) + " bytes after the last edge");
  return scans;
}

std::vector<GraphScan> readOctomapGraph(const std::string& path) {
  return parseOctomapGraph(readFileMaybeCompressed(path), path);
}

}  // namespace rmap::datasets
