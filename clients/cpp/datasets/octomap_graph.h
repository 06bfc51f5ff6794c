#pragma once
/// @file octomap_graph.h
/// Reader of OctoMap scan graphs (`.graph`, ScanGraph::writeBinary of
/// OctoMap 1.x): scans with the sensor pose each was taken from.
///
/// Layout, little-endian as OctoMap writes it on x86: u32 node count, then
/// per node its point cloud (u32 point count, then per point an i32 3 and
/// three f64 x y z), its pose (translation: i32 3, three f64; rotation: i32 4,
/// four f64 w x y z) and its u32 id; then u32 edge count and per edge u32
/// first id, u32 second id, a pose as above (the constraint) and an f64
/// weight. Points are in the sensor frame; OctoMap inserts them transformed
/// by the node's pose, with the pose's translation as the rays' origin.
/// Edges are checked but not returned (the poses already place the scans).

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace rmap::datasets {

struct GraphScan {
  uint32_t id = 0;
  Eigen::Isometry3d sensor_pose = Eigen::Isometry3d::Identity();  ///< sensor in the world frame (m)
  std::vector<Eigen::Vector3f> points_m;                          ///< sensor frame (m)
};

/// Parses the bytes of a `.graph` file.
/// @param source  name used in error messages (usually the path)
/// @throws std::runtime_error "<source>: offset <n>: ..." for truncated data,
///         a wrong vector or quaternion size tag, non-finite values, a zero
///         quaternion, an edge naming an unknown node, or bytes after the edges
std::vector<GraphScan> parseOctomapGraph(std::string_view bytes, const std::string& source);

/// Reads a file (optionally .gz/.bz2 compressed) with parseOctomapGraph.
std::vector<GraphScan> readOctomapGraph(const std::string& path);

}  // namespace rmap::datasets
