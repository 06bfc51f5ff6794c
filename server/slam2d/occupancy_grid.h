#pragma once
/// @file occupancy_grid.h
/// One level of the occupancy pyramid: log-odds per cell in growable chunks,
/// ray insertion of scans, and Hector's bilinear interpolation of the map
/// value and its gradient (Kohlbrecher et al., SSRR 2011, eqs. 4–6).
///
/// Cell (i, j) covers [i, i+1)·resolution × [j, j+1)·resolution in the map
/// frame; for interpolation its value sits at the cell centre, so a wall cell
/// marked by an endpoint is unbiased on average.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <span>

#include "slam2d/chunked_grid.h"

namespace rmap::slam2d {

/// How evidence changes a cell (log-odds, natural log).
struct OccupancyUpdate {
  float hit_log_odds = 1.0f;    ///< added to the cell holding a beam's endpoint (> 0)
  float miss_log_odds = -0.4f;  ///< added to each cell a beam crossed (< 0; 0: the beams' ends only, no ray walk)
  float min_log_odds = -2.0f;   ///< clamping keeps cells able to change their mind
  float max_log_odds = 3.5f;
  /// The matcher reads a cell of occupancy probability p as max(0, (p − floor) / (1 − floor)),
  /// unknown cells as 0. A cell crossed by few rays keeps p 0.3–0.4 (one miss: 0.40): read as p,
  /// such cells raise the map in front of a wall seen from afar, and Gauss–Newton pulls the
  /// scan toward the observer, so steps along a corridor come out short (0.12 % of their length
  /// on infinite-corridor, 0.3 % at 2.5 cm cells). A floor of 0.3 removes that there, but on
  /// other logs the steps then come out long and a sparse simulated tour drifts more: off until
  /// that is understood (BENCHMARKS §4, *The front end's steps come out short*).
  /// In [0, 1); 0 reads p itself.
  float value_floor_probability = 0.0f;
};

/// A beam for insertion, map frame (m): from the sensor to its end. Without
/// a return (`hit` false) only the crossed cells get free evidence.
struct Ray {
  Eigen::Vector2d end_m;
  bool hit = true;
};

class OccupancyGrid {
 public:
  /// Interpolated map value M ∈ [0, 1] (occupancy probability above
  /// OccupancyUpdate::value_floor_probability, rescaled; unknown = 0)
  /// and its gradient (per metre) at a point.
  struct Sample {
    float value = 0.0f;
    Eigen::Vector2f gradient_per_m = Eigen::Vector2f::Zero();
  };

  explicit OccupancyGrid(double resolution_m);
  /// A copy shares the cells until either side writes them (see ChunkedGrid).
  OccupancyGrid(const OccupancyGrid&) = default;
  OccupancyGrid& operator=(const OccupancyGrid&) = default;
  OccupancyGrid(OccupancyGrid&&) noexcept = default;
  OccupancyGrid& operator=(OccupancyGrid&&) noexcept = default;

  double resolution_m() const { return resolution_m_; }
  Eigen::Vector2i cellOf(const Eigen::Vector2d& p_m) const;
  /// Bounds of the cells observed so far (empty box when none).
  const Eigen::AlignedBox2i& knownCells() const { return known_; }
  /// NaN when never observed.
  float logOdds(const Eigen::Vector2i& cell) const;
  /// NaN when never observed.
  float probability(const Eigen::Vector2i& cell) const;
  /// Bilinear value and gradient at a map-frame point (m).
  Sample sample(const Eigen::Vector2d& p_m) const;
  /// Storage chunks, by address (see ChunkedGrid::forEachChunk).
  template <class Fn>
  void forEachChunk(Fn&& fn) const {
    cells_.forEachChunk(fn);
  }

  /// Inserts one scan: free evidence along each ray, hit evidence at each
  /// endpoint; within one call a cell changes at most once, and a hit wins over
  /// a miss (Hector's update marks). Rays longer than max_ray_m are cut there
  /// (as no return). All points must be finite.
  void insert(const Eigen::Vector2d& origin_m, std::span<const Ray> rays, const OccupancyUpdate& update,
              double max_ray_m);

 private:
  struct Cell {
    float log_odds = std::numeric_limits<float>::quiet_NaN();
    float value = 0.0f;   ///< what the matcher reads (see value_floor_probability), 0 while unknown
    uint32_t mark = 0;    ///< 2·insertion + (1 if hit) of the last change
  };

  using Cursor = ChunkedGrid<Cell>::Cursor;
  void miss(int x, int y, const OccupancyUpdate& update, Cursor& cursor);
  void hit(int x, int y, const OccupancyUpdate& update, Cursor& cursor);
  void apply(Cell& cell, float delta, const OccupancyUpdate& update, int x, int y);
  float value(int x, int y) const {
    const Cell* c = cells_.find(x, y);
    return c ? c->value : 0.0f;
  }

  double resolution_m_;
  double inv_resolution_;
  ChunkedGrid<Cell> cells_;
  Eigen::AlignedBox2i known_;
  uint32_t insertion_ = 0;
};

}  // namespace rmap::slam2d
