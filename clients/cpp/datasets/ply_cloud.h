#pragma once
/// @file ply_cloud.h
/// Reader of point clouds in the PLY format (Turk 1994, the variant written by
/// CloudCompare, PCL and Open3D): the `vertex` element's x, y, z and every
/// other scalar vertex property (intensity, ring, colour, ...) as floats.
///
/// Formats ascii, binary_little_endian and binary_big_endian; property types
/// char/uchar/short/ushort/int/uint/float/double and their int8…float64
/// aliases. Elements other than `vertex` are skipped when they come after it
/// or have only scalar properties; list properties are accepted in them only
/// in ascii files (one element per line). Points are returned as stored (no
/// filtering of no-returns; the caller knows the sensor's convention).

#include <Eigen/Core>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace rmap::datasets {

struct PlyCloud {
  std::vector<Eigen::Vector3f> points_m;                 ///< x y z of every vertex, in the file's units (metres for lidar data)
  std::map<std::string, std::vector<float>> scalars;     ///< other scalar vertex properties by name, one value per vertex
};

/// Parses PLY content.
/// @param source  name used in error messages (usually the path)
/// @throws std::runtime_error "<source>: ..." for a malformed header (with
///         its line number), a missing x/y/z, an unsupported format or type,
///         a vertex list property, truncated binary data or a bad ascii number
PlyCloud parsePlyCloud(std::string_view content, const std::string& source);

/// Reads a file (optionally .gz/.bz2 compressed) with parsePlyCloud.
PlyCloud readPlyCloud(const std::string& path);

}  // namespace rmap::datasets
