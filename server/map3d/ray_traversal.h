#pragma once
/// @file ray_traversal.h
/// 3D DDA (Amanatides & Woo) over base cells, with OctoMap's arithmetic
/// (float points and direction, double step parameters) so that a ray crosses
/// exactly the cells OctoMap's computeRayKeys lists.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#include "map3d/cell_key.h"

namespace rmap::map3d {

/// Walks the cells of a ray from its origin cell towards an end point.
class RayWalker {
 public:
  /// @param origin_m, end_m  metres; both must lie in addressable cells
  /// @return false when either point is not addressable (NaN/inf/out of range)
  bool init(const Grid& grid, const Eigen::Vector3f& origin_m, const Eigen::Vector3f& end_m) {
    if (!grid.cellChecked(origin_m, current_) || !grid.cellChecked(end_m, end_)) return false;
    Eigen::Vector3f direction = end_m - origin_m;
    // float sum of float squares, as OctoMap's Vector3::norm_sq
    const float norm_sq = direction.x() * direction.x() + direction.y() * direction.y() + direction.z() * direction.z();
    length_m_ = static_cast<float>(std::sqrt(static_cast<double>(norm_sq)));
    if (length_m_ > 0.0f) direction /= length_m_;
    const double res = grid.resolution();
    for (int a = 0; a < 3; ++a) {
      if (direction[a] > 0.0f) {
        step_[a] = 1;
      } else if (direction[a] < 0.0f) {
        step_[a] = -1;
      } else {
        step_[a] = 0;
      }
      if (step_[a] != 0) {
        double border = grid.center(current_[a]);
        border += static_cast<float>(step_[a] * res * 0.5);
        t_max_[a] = (border - origin_m[a]) / direction[a];
        t_delta_[a] = res / std::fabs(direction[a]);
      } else {
        t_max_[a] = std::numeric_limits<double>::max();
        t_delta_[a] = std::numeric_limits<double>::max();
      }
    }
    return true;
  }

  const CellKey& cell() const { return current_; }
  const CellKey& endCell() const { return end_; }
  bool atEnd() const { return current_ == end_; }
  /// metres from the origin to the point where the ray leaves the current cell
  double exitDistance() const { return std::min(std::min(t_max_[0], t_max_[1]), t_max_[2]); }
  float length() const { return length_m_; }

  /// Moves into the next cell along the ray.
  void step() {
    int dim;
    if (t_max_[0] < t_max_[1]) {
      dim = t_max_[0] < t_max_[2] ? 0 : 2;
    } else {
      dim = t_max_[1] < t_max_[2] ? 1 : 2;
    }
    current_[dim] += step_[dim];
    t_max_[dim] += t_delta_[dim];
  }

 private:
  CellKey current_, end_;
  int step_[3] = {0, 0, 0};
  double t_max_[3] = {0, 0, 0};
  double t_delta_[3] = {0, 0, 0};
  float length_m_ = 0.0f;
};

/// Calls `visit(const CellKey&)` for every cell the segment origin→end frees:
/// the origin cell and each crossed cell, never the end cell. Same cells and
/// order as OctoMap's computeRayKeys (which also stops early when rounding
/// would step past the end cell). A visitor returning bool stops the walk by
/// returning false.
/// @return false when origin or end is not addressable; nothing is visited then
template <class Visit>
bool traverseFreeCells(const Grid& grid, const Eigen::Vector3f& origin_m, const Eigen::Vector3f& end_m, Visit&& visit) {
  RayWalker walker;
  if (!walker.init(grid, origin_m, end_m)) return false;
  if (walker.atEnd()) return true;
  auto call = [&](const CellKey& c) {
    if constexpr (std::is_same_v<decltype(visit(c)), bool>) {
      return visit(c);
    } else {
      visit(c);
      return true;
    }
  };
  if (!call(walker.cell())) return true;
  const double length = walker.length();
  while (true) {
    walker.step();
    if (walker.atEnd()) break;
    if (walker.exitDistance() > length) break;
    if (!call(walker.cell())) break;
  }
  return true;
}

}  // namespace rmap::map3d
