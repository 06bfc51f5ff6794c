#pragma once
/// @file probability_raster.h
/// A dense, immutable occupancy-probability raster of a submap, the input of
/// the correlative (branch-and-bound) matcher: one float per cell, row-major,
/// so the matcher's inner loop is one load per point instead of a hash probe.
///
/// Cell (x, y) covers [origin + x·res, origin + (x+1)·res) × [origin + y·res,
/// origin + (y+1)·res) in the map frame (metres); a point falls in the cell
/// floor((p − origin) / res), the convention of OccupancyGrid::cellOf.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <span>
#include <vector>

#include "slam2d/occupancy_grid.h"
#include "slam2d/pose2.h"

namespace rmap::slam2d {

struct ProbabilityRaster {
  Eigen::Vector2d origin_m = Eigen::Vector2d::Zero();  ///< map-frame position of cell (0,0)'s lower-left corner
  double resolution_m = 0.05;                          ///< cell edge (m), > 0
  int width = 0;                                       ///< cells along x, > 0
  int height = 0;                                      ///< cells along y, > 0
  /// Row-major (y · width + x) occupancy probability in [0, 1]; never-observed
  /// cells hold a low value chosen by the builder (`unknown_p`).
  std::vector<float> p;
  /// Value of every cell outside the raster (the builders set it to `unknown_p`).
  float outside_p = 0.0f;

  /// Probability of a cell; `outside_p` outside [0, width) × [0, height).
  float at(int x, int y) const {
    return x >= 0 && y >= 0 && x < width && y < height
               ? p[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)]
               : outside_p;
  }
  /// Cell holding a map-frame point (m): floor((p − origin) · (1 / resolution)).
  /// Coordinates beyond ±10^9 cells are clamped there (far off any raster).
  Eigen::Vector2i cellOf(const Eigen::Vector2d& p_m) const {
    const double inv = 1.0 / resolution_m;
    return {floorToInt((p_m.x() - origin_m.x()) * inv), floorToInt((p_m.y() - origin_m.y()) * inv)};
  }
  /// floor(v) as an int, without the libm call (the matcher floors ~10⁶ values per search).
  static int floorToInt(double v) {
    v = std::min(std::max(v, -1e9), 1e9);  // not std::clamp: this form compiles to minsd/maxsd
    const int i = static_cast<int>(v);  // truncates toward zero
    return v < i ? i - 1 : i;
  }
  /// @throws std::invalid_argument naming the first broken invariant (size,
  ///         resolution, a probability outside [0, 1] or not finite)
  void validate() const;
};

/// Copies the cells `cells` (inclusive bounds, in the grid's cell indices, as
/// OccupancyGrid::knownCells gives them) of an occupancy grid into a raster;
/// never-observed cells and cells outside the raster get `unknown_p`.
/// origin_m = cells.min() · resolution.
/// @throws std::invalid_argument for an empty box or `unknown_p` outside [0, 1]
ProbabilityRaster rasterFromGrid(const OccupancyGrid& grid, const Eigen::AlignedBox2i& cells, float unknown_p);

/// The raster with each cell replaced by the largest value within
/// ±radius_cells along x and y (a square max filter; radius 0: a copy), so a
/// wall seen from few poses is as thick as the endpoint scatter of another
/// view of it.
/// @throws std::invalid_argument for a negative radius
ProbabilityRaster maxFiltered(const ProbabilityRaster& raster, int radius_cells);

/// One scan for rasterFromScans: endpoints in the robot frame (m) and the
/// robot pose in the map frame; the sensor sits at the robot origin.
struct PosedScan {
  Pose2 pose;
  std::span<const Eigen::Vector2d> points_robot;
};

/// Rasterises scans at their poses with the ray-casting occupancy update
/// (OccupancyGrid::insert: free evidence along each beam, hit at its end),
/// over the observed cells grown by `margin_cells` on every side.
/// @throws std::invalid_argument for no observed cell, a bad resolution,
///         `unknown_p` outside [0, 1], a negative margin or non-finite input
ProbabilityRaster rasterFromScans(std::span<const PosedScan> scans, double resolution_m, float unknown_p,
                                  const OccupancyUpdate& update = {}, double max_ray_m = 100.0,
                                  int margin_cells = 0);

}  // namespace rmap::slam2d
