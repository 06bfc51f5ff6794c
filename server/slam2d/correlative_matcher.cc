#include "slam2d/correlative_matcher.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rmap::slam2d {

/// The scan's cells at one lattice rotation, relative to the centre translation.
struct CorrelativeMatcher::Rotation {
  double theta_rad = 0.0;
  std::vector<Eigen::Vector2i> cells;
};

/// A block of 2^level × 2^level translations starting at (dx, dy) cells, at one
/// rotation, with the upper bound of its scores (exact score at level 0).
struct CorrelativeMatcher::Candidate {
  int rotation = 0;
  int dx = 0, dy = 0;
  int level = 0;
  double score = 0.0;
};

void CorrelativeMatcherOptions::validate() const {
  if (branch_levels < 1 || branch_levels > 16)
    throw std::invalid_argument("correlative matcher: branch_levels must be in [1, 16], got " +
                                std::to_string(branch_levels));
  if (!(angular_step_rad >= 0.0) || !std::isfinite(angular_step_rad))
    throw std::invalid_argument("correlative matcher: angular_step_rad must be finite and ≥ 0 (0 = from the scan)");
}

CorrelativeMatcher::CorrelativeMatcher(ProbabilityRaster raster, CorrelativeMatcherOptions options)
    : raster_(std::move(raster)), options_(options) {
  raster_.validate();
  options_.validate();
  levels_.resize(static_cast<size_t>(options_.branch_levels));
  levels_[0] = {0, raster_.width, raster_.height, raster_.p};
  const float outside = raster_.outside_p;
  // Level h from level h−1: a 2^h window is two 2^(h−1) windows half a window
  // apart, first along x, then along y, so each level costs O(cells).
  for (size_t h = 1; h < levels_.size(); ++h) {
    const Level& below = levels_[h - 1];
    const int half = 1 << (h - 1);
    Level& level = levels_[h];
    level.offset = (1 << h) - 1;
    level.width = raster_.width + level.offset;
    level.height = raster_.height + level.offset;
    auto get = [&](int x, int y) {  // level h−1 at raster cell (x, y)
      const int sx = x + below.offset, sy = y + below.offset;
      return sx >= 0 && sy >= 0 && sx < below.width && sy < below.height
                 ? below.v[static_cast<size_t>(sy) * static_cast<size_t>(below.width) + static_cast<size_t>(sx)]
                 : outside;
    };
    // Pooled along x only, rows as in level h (row index sy ↔ raster row sy − offset).
    std::vector<float> along_x(static_cast<size_t>(level.width) * static_cast<size_t>(level.height));
    for (int sy = 0; sy < level.height; ++sy)
      for (int sx = 0; sx < level.width; ++sx) {
        const int x = sx - level.offset, y = sy - level.offset;
        along_x[static_cast<size_t>(sy) * static_cast<size_t>(level.width) + static_cast<size_t>(sx)] =
            std::max(get(x, y), get(x + half, y));
      }
    level.v.resize(along_x.size());
    for (int sy = 0; sy < level.height; ++sy)
      for (int sx = 0; sx < level.width; ++sx) {
        const size_t i = static_cast<size_t>(sy) * static_cast<size_t>(level.width) + static_cast<size_t>(sx);
        const float above = sy + half < level.height ? along_x[i + static_cast<size_t>(half) * level.width] : outside;
        level.v[i] = std::max(along_x[i], above);
      }
  }
}

SearchLattice CorrelativeMatcher::lattice(std::span<const Eigen::Vector2d> points_robot, double window_m,
                                          double window_rad) const {
  if (!(window_m >= 0.0) || !std::isfinite(window_m))
    throw std::invalid_argument("correlative matcher: window_m must be finite and ≥ 0, got " +
                                std::to_string(window_m));
  if (!(window_rad >= 0.0 && window_rad <= std::numbers::pi))
    throw std::invalid_argument("correlative matcher: window_rad must be in [0, π], got " +
                                std::to_string(window_rad));
  // A small tolerance so a window that is an exact multiple of the step keeps its last step.
  const double linear = std::floor(window_m / raster_.resolution_m + 1e-9);
  if (linear > kMaxLinearSteps)
    throw std::invalid_argument("correlative matcher: window_m of " + std::to_string(window_m) + " m is over " +
                                std::to_string(kMaxLinearSteps) + " cells");
  SearchLattice lattice;
  lattice.linear_steps = static_cast<int>(linear);
  lattice.angular_step_rad = options_.angular_step_rad;
  if (lattice.angular_step_rad <= 0.0) {
    double d_max = 0.0;
    for (const Eigen::Vector2d& p : points_robot) d_max = std::max(d_max, p.norm());
    const double r = raster_.resolution_m;
    lattice.angular_step_rad =
        d_max > 0.0 ? std::acos(std::max(-1.0, 1.0 - r * r / (2.0 * d_max * d_max))) : std::numbers::pi;
  }
  lattice.angular_steps = static_cast<int>(std::floor(window_rad / lattice.angular_step_rad + 1e-9));
  return lattice;
}

std::vector<CorrelativeMatcher::Rotation> CorrelativeMatcher::discretise(std::span<const Eigen::Vector2d> points_robot,
                                                                         const Pose2& center,
                                                                         const SearchLattice& lattice) const {
  std::vector<Rotation> rotations;
  rotations.reserve(static_cast<size_t>(2 * lattice.angular_steps + 1));
  for (int k = -lattice.angular_steps; k <= lattice.angular_steps; ++k) {
    Rotation rotation;
    rotation.theta_rad = center.theta_rad + k * lattice.angular_step_rad;
    const Pose2 pose{center.x_m, center.y_m, rotation.theta_rad};
    rotation.cells.reserve(points_robot.size());
    for (const Eigen::Vector2d& p : points_robot) rotation.cells.push_back(raster_.cellOf(pose * p));
    rotations.push_back(std::move(rotation));
  }
  return rotations;
}

double CorrelativeMatcher::meanAt(const Level& level, const Rotation& rotation, int dx, int dy) const {
  const int ox = dx + level.offset, oy = dy + level.offset;
  const float outside = raster_.outside_p;
  const size_t stride = static_cast<size_t>(level.width);
  double sum = 0.0;
  for (const Eigen::Vector2i& c : rotation.cells) {
    const int x = c.x() + ox, y = c.y() + oy;
    sum += static_cast<unsigned>(x) < static_cast<unsigned>(level.width) &&
                   static_cast<unsigned>(y) < static_cast<unsigned>(level.height)
               ? level.v[static_cast<size_t>(y) * stride + static_cast<size_t>(x)]
               : outside;
  }
  return sum / static_cast<double>(rotation.cells.size());
}

void CorrelativeMatcher::descend(const std::vector<Rotation>& rotations, const Candidate& block, int linear_steps,
                                 double min_score, std::optional<Candidate>& best) const {
  if (block.level == 0) {
    if (!best || block.score > best->score) best = block;
    return;
  }
  const int level = block.level - 1;
  const int step = 1 << level;
  Candidate children[4];
  int count = 0;
  for (int dy = block.dy; dy <= block.dy + step && dy <= linear_steps; dy += step)
    for (int dx = block.dx; dx <= block.dx + step && dx <= linear_steps; dx += step) {
      Candidate child{block.rotation, dx, dy, level,
                      meanAt(levels_[static_cast<size_t>(level)], rotations[static_cast<size_t>(block.rotation)], dx, dy)};
      if (child.score < min_score || (best && child.score <= best->score)) continue;
      int at = count++;  // insertion keeps the (at most four) children sorted, best bound first
      for (; at > 0 && children[at - 1].score < child.score; --at) children[at] = children[at - 1];
      children[at] = child;
    }
  for (int i = 0; i < count; ++i) {
    if (best && children[i].score <= best->score) break;
    descend(rotations, children[i], linear_steps, min_score, best);
  }
}

std::optional<CorrelativeMatch> CorrelativeMatcher::match(std::span<const Eigen::Vector2d> points_robot,
                                                          const Pose2& center, double window_m, double window_rad,
                                                          double min_score) const {
  const SearchLattice lattice = this->lattice(points_robot, window_m, window_rad);
  if (!(min_score >= 0.0 && min_score <= 1.0))
    throw std::invalid_argument("correlative matcher: min_score must be in [0, 1], got " + std::to_string(min_score));
  if (!center.isFinite()) throw std::invalid_argument("correlative matcher: the centre pose is not finite");
  for (const Eigen::Vector2d& p : points_robot)
    if (!p.allFinite()) throw std::invalid_argument("correlative matcher: a point is not finite");
  if (points_robot.empty()) return std::nullopt;

  const std::vector<Rotation> rotations = discretise(points_robot, center, lattice);
  const int linear_steps = lattice.linear_steps;
  // The coarsest level worth using: one block spanning the whole window.
  int top = 0;
  while (top + 1 < static_cast<int>(levels_.size()) && (1 << top) < 2 * linear_steps + 1) ++top;
  const int step = 1 << top;
  std::vector<Candidate> candidates;
  for (int r = 0; r < static_cast<int>(rotations.size()); ++r)
    for (int dy = -linear_steps; dy <= linear_steps; dy += step)
      for (int dx = -linear_steps; dx <= linear_steps; dx += step) {
        const double bound = meanAt(levels_[static_cast<size_t>(top)], rotations[static_cast<size_t>(r)], dx, dy);
        if (bound >= min_score) candidates.push_back({r, dx, dy, top, bound});
      }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
  std::optional<Candidate> best;
  for (const Candidate& c : candidates) {
    if (best && c.score <= best->score) break;
    descend(rotations, c, linear_steps, min_score, best);
  }
  if (!best) return std::nullopt;
  const double r = raster_.resolution_m;
  return CorrelativeMatch{{center.x_m + best->dx * r, center.y_m + best->dy * r,
                           normalizeAngle(rotations[static_cast<size_t>(best->rotation)].theta_rad)},
                          best->score};
}

}  // namespace rmap::slam2d
