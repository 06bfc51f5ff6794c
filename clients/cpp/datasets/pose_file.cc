#include "datasets/pose_file.h"

#include <cmath>

#include "datasets/carmen_log.h"
#include "datasets/compressed_file.h"
#include "datasets/text_fields.h"

namespace rmap::datasets {

std::vector<StampedPose3> parsePoseFile(std::string_view text, const std::string& source) {
  TextLines lines(text);
  std::string_view line;
  std::string_view f[13];
  size_t form = 0;  // fields per line of this file
  std::vector<StampedPose3> poses;
  while (lines.next(line)) {
    const size_t n = splitFields(stripComment(line), f, 13);
    if (n == 0) continue;
    if (n != 12 && n != 8) {
      throwAt(source, lines.number(), std::to_string(n) + " fields: a pose line has 12 (KITTI 3x4 matrix) or 8 (TUM "
                                                          "stamp x y z qx qy qz qw)");
    }
    if (form != 0 && n != form) {
      throwAt(source, lines.number(), std::to_string(n) + " fields where the file's first pose has " +
                                          std::to_string(form));
    }
    form = n;
    double v[12];
    for (size_t i = 0; i < n; ++i) {
      v[i] = parseNumber(f[i], source, lines.number());
      if (!std::isfinite(v[i])) throwAt(source, lines.number(), "field " + std::to_string(i + 1) + " is not finite");
    }
    StampedPose3 p;
    p.line = lines.number();
    if (n == 12) {
      Eigen::Matrix3d r;
      r << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
      if (!(r.transpose() * r).isApprox(Eigen::Matrix3d::Identity(), 1e-3) || r.determinant() < 0.0) {
        throwAt(source, lines.number(), "the 3x3 rotation is not orthonormal");
      }
      p.pose.linear() = Eigen::Quaterniond(r).normalized().toRotationMatrix();
      p.pose.translation() = Eigen::Vector3d(v[3], v[7], v[11]);
    } else {
      p.stamp_ns = parseCarmenStampNs(f[0], source, lines.number());  // exact for plain decimals
      const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
      if (!(q.norm() > 1e-9)) throwAt(source, lines.number(), "the quaternion is zero");
      p.pose.linear() = q.normalized().toRotationMatrix();
      p.pose.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    }
    poses.push_back(p);
  }
  return poses;
}

std::vector<StampedPose3> readPoseFile(const std::string& path) {
  return parsePoseFile(readFileMaybeCompressed(path), path);
}

}  // namespace rmap::datasets
