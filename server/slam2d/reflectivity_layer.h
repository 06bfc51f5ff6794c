#pragma once
/// @file reflectivity_layer.h
/// Fused calibrated reflectivity per cell of the finest grid level: running
/// mean and spread (Welford) of the reflectivity ρ of every return that
/// ended in the cell, and a bilinear interpolation over the cells that hold
/// any, for the scan matcher's reflectivity residual.

#include <Eigen/Core>
#include <cstdint>

#include "slam2d/chunked_grid.h"

namespace rmap::slam2d {

/// Reflectivity of one cell (ρ, dimensionless, 1 = the calibration's reference surface).
struct ReflectivityCell {
  float mean = 0.0f;
  float stddev = 0.0f;  ///< population standard deviation of the fused returns
  uint32_t count = 0;   ///< returns fused; 0 = no reflectivity known
};

class ReflectivityLayer {
 public:
  /// Interpolated reflectivity and its gradient (per metre); `support` is
  /// the summed bilinear weight of the cells that hold reflectivity (0 = none near).
  struct Sample {
    float value = 0.0f;
    Eigen::Vector2f gradient_per_m = Eigen::Vector2f::Zero();
    float support = 0.0f;
  };

  explicit ReflectivityLayer(double resolution_m);

  ReflectivityCell at(const Eigen::Vector2i& cell) const;
  /// Fuses one finite reflectivity into a cell.
  void add(const Eigen::Vector2i& cell, float reflectivity);
  /// Bilinear over the cells with reflectivity only (weights renormalised),
  /// cell values at cell centres, like OccupancyGrid::sample.
  Sample sample(const Eigen::Vector2d& p_m) const;
  /// Storage chunks, by address (see ChunkedGrid::forEachChunk).
  template <class Fn>
  void forEachChunk(Fn&& fn) const {
    cells_.forEachChunk(fn);
  }

 private:
  struct Cell {
    uint32_t count = 0;
    float mean = 0.0f;
    float m2 = 0.0f;  ///< Welford's sum of squared deviations
  };

  double inv_resolution_;
  ChunkedGrid<Cell> cells_;
};

}  // namespace rmap::slam2d
