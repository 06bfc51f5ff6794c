#pragma once
/// @file fake_grid2d.h
/// A Grid2dSource of explicitly set cells, for the 2D layer tests.

#include <cmath>
#include <map>
#include <utility>

#include "app/layer_tiles.h"

namespace rmap::app::testing {

class FakeGrid2d : public Grid2dSource {
 public:
  explicit FakeGrid2d(double resolution_m) : resolution_m_(resolution_m) {}
  void set(int x, int y, float probability, float reflectivity = NAN) {
    cells_[{x, y}] = {probability, reflectivity};
    known_.extend(Eigen::Vector2i(x, y));
  }
  double resolutionM() const override { return resolution_m_; }
  Eigen::AlignedBox2i knownCells() const override { return known_; }
  float probability(const Eigen::Vector2i& c) const override {
    const auto it = cells_.find({c.x(), c.y()});
    return it == cells_.end() ? NAN : it->second.first;
  }
  float reflectivity(const Eigen::Vector2i& c) const override {
    const auto it = cells_.find({c.x(), c.y()});
    return it == cells_.end() ? NAN : it->second.second;
  }

 private:
  double resolution_m_;
  Eigen::AlignedBox2i known_;  // default-constructed: empty
  std::map<std::pair<int, int>, std::pair<float, float>> cells_;
};

}  // namespace rmap::app::testing
