#pragma once
/// @file navigable.h
/// Where a sensor carrier (robot, legged robot, person) can move in a
/// VoxelWorld: a multi-level 2.5D grid of standing places.
///
/// The horizontal plane is divided into cells of a whole number of voxels. A
/// node is a cell plus a standing surface in it: an occupied voxel level with
/// a free one above (in any voxel column of the cell). A node is navigable when
///  - the carrier's body, a vertical cylinder of radius clearance_m around any
///    point of the cell from body_bottom_m (or lower, see below) up to
///    sensor_height_m + clearance_m above the surface, holds no occupied voxel,
///    so the sensor keeps clearance_m from every occupied voxel wherever it is
///    in the cell (the cylinder starts at sensor_height_m − clearance_m if that
///    is lower than body_bottom_m);
///  - the column above the surface is free up to the top of the body;
///  - the body fits below the top of the grid (so a roof is not a floor);
///  - in a world with known free space, the sensor's voxel is known free in
///    every voxel column of the cell (only observed space is known to be empty).
/// Neighbouring nodes (8-neighbourhood) connect when their surfaces differ by
/// at most max_step_m; a diagonal move also needs both side cells to connect
/// to both ends, so paths never cut corners.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <utility>
#include <vector>

#include "sim/voxel_world.h"

namespace rmap::sim {

struct NavigableOptions {
  double sensor_height_m = 1.0;  ///< sensor above the standing surface, metres, ≥ clearance_m
  double clearance_m = 0.25;     ///< metres, > 0: free radius around the sensor and the body
  double body_bottom_m = 0.4;    ///< metres, ≥ 0: lower obstacles are stepped over (stair treads, thresholds)
  double max_step_m = 0.25;      ///< metres, ≥ 0: largest height change between neighbouring cells
  double cell_m = 0.1;           ///< cell edge, metres, > 0; rounded to a whole number (≥ 1) of voxels

  /// @throws std::invalid_argument naming the first bad parameter
  void validate() const;
};

class NavigableSpace {
 public:
  struct Node {
    int32_t cx = 0, cy = 0;     ///< cell indices
    int32_t surface_voxel = 0;  ///< global z index of the occupied voxel stood on
  };

  NavigableSpace(const VoxelWorld& world, const NavigableOptions& options);

  const std::vector<Node>& nodes() const { return nodes_; }
  size_t size() const { return nodes_.size(); }
  int cellsX() const { return cells_x_; }
  int cellsY() const { return cells_y_; }
  double cellSize() const { return cell_m_; }
  const NavigableOptions& options() const { return options_; }

  /// Metric extent of a cell (clipped to the world's grid).
  Eigen::AlignedBox2d cellBox(int cx, int cy) const;
  /// Cell containing a horizontal position; false outside the grid.
  bool cellOf(const Eigen::Vector2d& xy_m, int& cx, int& cy) const;
  /// Height of the standing surface (top face of the voxel stood on), metres.
  double surfaceZ(int node) const { return (nodes_[node].surface_voxel + 1) * voxel_m_; }
  /// Sensor height of a node, metres: surfaceZ + sensor_height_m.
  double sensorZ(int node) const { return surfaceZ(node) + options_.sensor_height_m; }
  /// Sensor at the cell centre.
  Eigen::Vector3d sensorPosition(int node) const;

  /// Nodes of a cell, as the index range [first, second), lowest surface first.
  std::pair<int, int> nodesInCell(int cx, int cy) const {
    const size_t c = static_cast<size_t>(cy) * cells_x_ + cx;
    return {cell_start_[c], cell_start_[c + 1]};
  }
  /// The node of a cell whose surface is within max_step_m of surface_voxel
  /// (the closest one), or −1.
  int nodeNear(int cx, int cy, int surface_voxel) const;

  /// Calls f(neighbour node, move length in metres) for every connected neighbour.
  template <class F>
  void forEachNeighbour(int node, F&& f) const;

  /// Connected component id of a node; components are numbered by decreasing size.
  int component(int node) const { return component_[node]; }
  size_t componentSize(int id) const { return component_sizes_[id]; }
  size_t componentCount() const { return component_sizes_.size(); }
  /// Height of the most common standing surface in the largest component
  /// (the main floor), metres. NaN if there are no nodes.
  double dominantFloorZ() const;

 private:
  bool compatible(int cx, int cy, int k1, int k2) const;

  NavigableOptions options_;
  double voxel_m_;
  Eigen::Vector3i min_voxel_;
  Eigen::Vector3i dims_;
  int cell_voxels_;
  double cell_m_;
  int cells_x_ = 0, cells_y_ = 0;
  int max_step_voxels_;
  std::vector<Node> nodes_;       ///< sorted by cell (y-major), then surface
  std::vector<int> cell_start_;   ///< per cell: first node index; one extra entry at the end
  std::vector<int> component_;
  std::vector<size_t> component_sizes_;
};

template <class F>
void NavigableSpace::forEachNeighbour(int node, F&& f) const {
  const Node& n = nodes_[node];
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      if (dx == 0 && dy == 0) continue;
      const int cx = n.cx + dx, cy = n.cy + dy;
      if (cx < 0 || cy < 0 || cx >= cells_x_ || cy >= cells_y_) continue;
      const auto [first, last] = nodesInCell(cx, cy);
      for (int other = first; other < last; ++other) {
        const int k = nodes_[other].surface_voxel;
        if (std::abs(k - n.surface_voxel) > max_step_voxels_) continue;
        if (dx != 0 && dy != 0 &&
            (!compatible(n.cx + dx, n.cy, n.surface_voxel, k) || !compatible(n.cx, n.cy + dy, n.surface_voxel, k))) {
          continue;
        }
        const double horizontal = (dx != 0 && dy != 0 ? std::numbers::sqrt2 : 1.0) * cell_m_;
        const double vertical = (k - n.surface_voxel) * voxel_m_;
        f(other, std::sqrt(horizontal * horizontal + vertical * vertical));
      }
    }
  }
}

}  // namespace rmap::sim
