#pragma once
/// @file pcd_cloud.h
/// Reader of point clouds in PCL's PCD format (v0.7, also the v0.6 header
/// without VERSION): the x, y, z fields and, when present, `intensity`.
///
/// DATA ascii (one point per line) and binary (packed records, point-major);
/// binary_compressed is refused with a message saying so. Field types I/U/F
/// of sizes 1, 2, 4, 8; fields with COUNT > 1 are skipped over (only x, y, z
/// and intensity must have COUNT 1). Points are returned as stored, including
/// the NaN points of organised clouds (the caller drops what it cannot use).

#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

namespace rmap::datasets {

struct PcdCloud {
  std::vector<Eigen::Vector3f> points_m;  ///< x y z of every point, in the file's units (metres for lidar data)
  std::vector<float> intensities;         ///< one per point, or empty without an `intensity` field
};

/// Parses PCD content.
/// @param source  name used in error messages (usually the path)
/// @throws std::runtime_error "<source>:<line>: ..." for a malformed header
///         (unknown keyword order, missing x/y/z, bad type or size, POINTS
///         other than WIDTH·HEIGHT) or a bad ascii value, and
///         "<source>: offset <n>: ..." for truncated binary data
PcdCloud parsePcdCloud(std::string_view content, const std::string& source);

/// Reads a file (optionally .gz/.bz2 compressed) with parsePcdCloud.
PcdCloud readPcdCloud(const std::string& path);

}  // namespace rmap::datasets
