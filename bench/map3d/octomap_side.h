#pragma once
/// @file octomap_side.h
/// OctoMap 1.9 driven with the same parameters as a CuboidMap, for side-by-side runs.

#include <functional>
#include <memory>
#include <vector>

#include "datasets/point_scan.h"
#include "map3d/cuboid_map.h"

namespace octomap {
class OcTree;
class Pointcloud;
}

namespace rmap::bench {

class OctomapSide {
 public:
  /// @param threads  OpenMP threads for OctoMap's computeUpdate
  OctomapSide(double resolution_m, const map3d::OccupancyParams& params, int threads);
  ~OctomapSide();

  /// Converts scans to OctoMap point clouds ahead of time, so insert() times
  /// OctoMap's work alone.
  void prepare(const std::vector<datasets::PointScan>& scans);
  /// Inserts prepared scan i: insertPointCloud for the beam model; for the
  /// endpoint model one hit per distinct endpoint cell (OctoMap has no such mode).
  void insert(size_t i);
  /// Prunes the tree (OctoMap's own compression, done once after insertion).
  void finish();

  map3d::CellState state(const map3d::CellKey& cell) const;
  size_t memoryBytes() const;
  size_t leaves() const;
  /// Calls fn(cell) for each known base cell with its state (pruned leaves expanded).
  void forEachKnownCell(const std::function<void(const map3d::CellKey&, map3d::CellState)>& fn) const;
  /// Known base cells (sum of leaf volumes in cells).
  uint64_t knownCells() const;

 private:
  std::unique_ptr<octomap::OcTree> tree_;
  std::vector<octomap::Pointcloud> clouds_;
  std::vector<Eigen::Vector3f> origins_;
  map3d::OccupancyParams params_;
};

}  // namespace rmap::bench
