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
#include <utility>

#include "map3d/cell_key.h"

namespace rmap::map3d {

/// Walks the cells of a ray from its origin cell towards an end point.
class RayWalker {
 public:
  /// @param origin_m, end_m  metres; both must lie in addressable cells
  /// @return false when either point is not addressable (NaN/inf/out of range)
  bool init(const Grid& grid, const Eigen::Vector3f& origin_m, const Eigen::Vector3f& end_m) {
    CellKey origin_cell, end_cell;
    if (!grid.cellChecked(origin_m, origin_cell) || !grid.cellChecked(end_m, end_cell)) return false;
    init(grid, origin_m, origin_cell, end_m, end_cell);
    return true;
  }

  /// The same with the cells of both points already known (`grid.cellChecked`
  /// succeeded for them), so a caller that has them pays no second look-up.
  void init(const Grid& grid, const Eigen::Vector3f& origin_m, const CellKey& origin_cell,
            const Eigen::Vector3f& end_m, const CellKey& end_cell) {
    current_ = origin_cell;
    end_ = end_cell;
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

  /// Steps on until the end cell or the end of the segment, calling
  /// `call(const CellKey&) -> bool` for each cell entered (false stops). The
  /// same steps as step(), with the state held in locals (registers) rather
  /// than in the walker's arrays; the walker itself is left where it was.
  template <class Call>
  void walkRest(Call&& call) const {
    const double length = length_m_;
    int32_t cx = current_.x, cy = current_.y, cz = current_.z;
    const int32_t ex = end_.x, ey = end_.y, ez = end_.z;
    const int32_t sx = step_[0], sy = step_[1], sz = step_[2];
    double tx = t_max_[0], ty = t_max_[1], tz = t_max_[2];
    const double dx = t_delta_[0], dy = t_delta_[1], dz = t_delta_[2];
    while (true) {
      if (tx < ty) {
        if (tx < tz) {
          cx += sx;
          tx += dx;
        } else {
          cz += sz;
          tz += dz;
        }
      } else if (ty < tz) {
        cy += sy;
        ty += dy;
      } else {
        cz += sz;
        tz += dz;
      }
      if (cx == ex && cy == ey && cz == ez) break;
      if (std::min(std::min(tx, ty), tz) > length) break;
      if (!call(CellKey{cx, cy, cz})) break;
    }
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
/// @param origin_cell, end_cell  the cells of origin_m and end_m, as
///   `grid.cellChecked` gives them (so both are addressable)
template <class Visit>
void traverseFreeCells(const Grid& grid, const Eigen::Vector3f& origin_m, const CellKey& origin_cell,
                       const Eigen::Vector3f& end_m, const CellKey& end_cell, Visit&& visit) {
  if (origin_cell == end_cell) return;
  RayWalker walker;
  walker.init(grid, origin_m, origin_cell, end_m, end_cell);
  auto call = [&](const CellKey& c) {
    if constexpr (std::is_same_v<decltype(visit(c)), bool>) {
      return visit(c);
    } else {
      visit(c);
      return true;
    }
  };
  if (!call(walker.cell())) return;
  walker.walkRest(call);
}

/// The same for points whose cells are not known yet.
/// @return false when origin or end is not addressable; nothing is visited then
template <class Visit>
bool traverseFreeCells(const Grid& grid, const Eigen::Vector3f& origin_m, const Eigen::Vector3f& end_m, Visit&& visit) {
  CellKey origin_cell, end_cell;
  if (!grid.cellChecked(origin_m, origin_cell) || !grid.cellChecked(end_m, end_cell)) return false;
  traverseFreeCells(grid, origin_m, origin_cell, end_m, end_cell, std::forward<Visit>(visit));
  return true;
}

}  // namespace rmap::map3d
