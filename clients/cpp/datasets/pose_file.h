#pragma once
/// @file pose_file.h
/// Reader of trajectory files: one pose per line, in either of two forms
/// (told apart by the field count of each line; one file uses one form):
/// - KITTI odometry: 12 numbers, the 3×4 matrix [R | t] row-major (the
///   pose of frame i in the frame of the first), no stamp;
/// - TUM RGB-D: 8 numbers `stamp_s x y z qx qy qz qw`.
/// Blank lines and '#' comments are skipped.

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rmap::datasets {

struct StampedPose3 {
  std::optional<int64_t> stamp_ns;  ///< TUM lines only
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  size_t line = 0;  ///< 1-based
};

/// @param source  name used in error messages (usually the path)
/// @throws std::runtime_error "<source>:<line>: ..." for a line of another
///         field count than 12 or 8 (or than the file's first), a malformed
///         or non-finite number, a rotation that is not orthonormal (KITTI,
///         within 1e-3) or a zero quaternion (TUM)
std::vector<StampedPose3> parsePoseFile(std::string_view text, const std::string& source);

/// Reads a file (plain, gzip or bzip2) with parsePoseFile.
std::vector<StampedPose3> readPoseFile(const std::string& path);

}  // namespace rmap::datasets
