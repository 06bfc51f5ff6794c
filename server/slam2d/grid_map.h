#pragma once
/// @file grid_map.h
/// The 2D map: an occupancy pyramid (level 0 finest, each level twice the
/// cell edge of the one below) and a reflectivity layer on the finest level.
/// Grows in every direction as robots go; the read interface answers about
/// the finest level.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <span>
#include <vector>

#include "slam2d/occupancy_grid.h"
#include "slam2d/reflectivity_layer.h"

namespace rmap::slam2d {

class GridMap2d {
 public:
  /// @param resolution_m  finest cell edge (m), > 0
  /// @param levels  ≥ 1
  /// @throws std::invalid_argument for a bad resolution or level count
  GridMap2d(double resolution_m, int levels);

  double resolution_m() const { return levels_.front().resolution_m(); }
  /// Cell holding a point (m, map frame): floor(p / resolution).
  Eigen::Vector2i cellOf(const Eigen::Vector2d& p_m) const { return levels_.front().cellOf(p_m); }
  /// Bounds of the cells observed so far, in cell indices (empty box when none).
  Eigen::AlignedBox2i knownCells() const { return levels_.front().knownCells(); }
  /// Log-odds of a cell, NaN when never observed.
  float logOdds(const Eigen::Vector2i& cell) const { return levels_.front().logOdds(cell); }
  /// Occupancy probability, NaN when unknown.
  float probability(const Eigen::Vector2i& cell) const { return levels_.front().probability(cell); }
  /// Fused calibrated reflectivity of a cell: mean, standard deviation, count (count 0 = none).
  ReflectivityCell reflectivity(const Eigen::Vector2i& cell) const { return reflectivity_.at(cell); }

  /// Pyramid access for the scan matcher.
  int levelCount() const { return static_cast<int>(levels_.size()); }
  const OccupancyGrid& level(int i) const { return levels_[static_cast<size_t>(i)]; }
  const ReflectivityLayer& reflectivityLayer() const { return reflectivity_; }
  bool empty() const { return levels_.front().knownCells().isEmpty(); }
  /// Storage chunks of every level and of the reflectivity layer, by address
  /// (copies share the ones neither side wrote since; see ChunkedGrid).
  template <class Fn>
  void forEachChunk(Fn&& fn) const {
    for (const OccupancyGrid& level : levels_) level.forEachChunk(fn);
    reflectivity_.forEachChunk(fn);
  }

  /// Inserts one scan into every level (see OccupancyGrid::insert).
  void insert(const Eigen::Vector2d& origin_m, std::span<const Ray> rays, const OccupancyUpdate& update,
              double max_ray_m);
  /// Fuses a return's reflectivity into the finest cell holding its endpoint.
  void addReflectivity(const Eigen::Vector2d& end_m, float reflectivity) {
    reflectivity_.add(cellOf(end_m), reflectivity);
  }
  void addReflectivityToCell(const Eigen::Vector2i& cell, float reflectivity) { reflectivity_.add(cell, reflectivity); }

 private:
  std::vector<OccupancyGrid> levels_;
  ReflectivityLayer reflectivity_;
};

}  // namespace rmap::slam2d
