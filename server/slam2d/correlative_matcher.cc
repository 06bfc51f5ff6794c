#include "slam2d/correlative_matcher.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rmap::slam2d {

/// The scan at one lattice rotation, relative to the centre translation.
struct CorrelativeMatcher::Rotation {
  double theta_rad = 0.0;
  std::vector<Eigen::Vector2i> cells;  ///< per point, in the caller's order (exact scores)
  /// For bounds: layout index of each point whose cells stay in the padded
  /// layout at every shift of the window (no checks needed) ...
  std::vector<int32_t> fast;
  std::vector<Eigen::Vector2i> slow;  ///< ... the cells of the others but ...
  uint32_t outside_sum = 0;           ///< ... those off the raster at every shift (outside_q each)
};

/// Consecutive rotations bounded together at the top level: per point, the box
/// of its cells over them, so a bound is the maximum over the box widened by
/// the block (two overlapping windows per axis: four lookups).
struct CorrelativeMatcher::RotationGroup {
  int first = 0, count = 0;       ///< rotations [first, first + count)
  std::vector<int32_t> fast;      ///< layout index of each box's lower-left cell ...
  std::vector<int32_t> right;     ///< ... its width − 1 in cells ...
  std::vector<int32_t> up;        ///< ... and height − 1 in layout rows (· stride)
  std::vector<Eigen::Vector4i> slow;  ///< boxes that may leave the layout: min x, min y, width − 1, height − 1
  uint32_t fixed_sum = 0;         ///< outside_q per box off the raster, 255 per box wider than a block
};

/// A block of 2^level × 2^level translations starting at (dx, dy) cells, at one
/// rotation: `score` is the quantised bound sum at level ≥ 1, the exact score at level 0.
struct CorrelativeMatcher::Candidate {
  int rotation = 0;
  int dx = 0, dy = 0;
  int level = 0;
  double score = 0.0;
};

/// What a search leaves out and when it stops: the ExcludedDisk in the
/// lattice's shift units (cells from the centre translation), and whether the
/// first pose reaching min_score ends it.
struct CorrelativeMatcher::Restriction {
  bool disk = false;
  double x = 0.0, y = 0.0, radius2 = 0.0;
  bool first_only = false;
  bool excludes(int dx, int dy) const { return disk && (dx - x) * (dx - x) + (dy - y) * (dy - y) <= radius2; }
  /// Every shift of the 2^level block from (dx, dy) is excluded (the disk is convex: its corners suffice).
  bool excludesBlock(int dx, int dy, int level) const {
    const int last = (1 << level) - 1;
    return excludes(dx, dy) && excludes(dx + last, dy) && excludes(dx, dy + last) && excludes(dx + last, dy + last);
  }
  bool done(const std::optional<Candidate>& best) const { return first_only && best.has_value(); }
};

void CorrelativeMatcherOptions::validate() const {
  if (branch_levels < 1 || branch_levels > 16)
    throw std::invalid_argument("correlative matcher: branch_levels must be in [1, 16], got " +
                                std::to_string(branch_levels));
  if (!(angular_step_rad >= 0.0) || !std::isfinite(angular_step_rad))
    throw std::invalid_argument("correlative matcher: angular_step_rad must be finite and ≥ 0 (0 = from the scan)");
  if (!(fast_window_m >= 0.0) || !std::isfinite(fast_window_m))
    throw std::invalid_argument("correlative matcher: fast_window_m must be finite and ≥ 0");
}

namespace {

/// Bounds are sums of probabilities quantised up to 1/255, so a level is a
/// quarter of the floats' memory and its sums are exact integers.
constexpr double kQuanta = 255.0;
// Bound sums (at most 255 per point) stay within uint32_t for any accepted search.
static_assert(255 * CorrelativeMatcher::kMaxPointRotations < (int64_t{1} << 32));

uint8_t quantiseUp(float p) {
  auto q = static_cast<int>(std::ceil(static_cast<double>(p) * kQuanta));
  if (q / kQuanta < p) ++q;  // ceil of a rounded product may fall short by one
  return static_cast<uint8_t>(std::clamp(q, 0, 255));
}

}  // namespace

CorrelativeMatcher::CorrelativeMatcher(ProbabilityRaster raster, CorrelativeMatcherOptions options)
    : raster_(std::move(raster)), options_(options) {
  raster_.validate();
  options_.validate();
  outside_q_ = quantiseUp(raster_.outside_p);
  if (options_.branch_levels == 1) return;  // brute force reads the raster only
  const double margin = std::ceil(options_.fast_window_m / raster_.resolution_m) + (1 << (options_.branch_levels - 1));
  const double stride = raster_.width + 2.0 * margin, rows = raster_.height + 2.0 * margin;
  if (stride * rows >= static_cast<double>(int64_t{1} << 31))
    throw std::invalid_argument("correlative matcher: raster of " + std::to_string(raster_.width) + " x " +
                                std::to_string(raster_.height) + " cells padded for fast_window_m " +
                                std::to_string(options_.fast_window_m) + " m is too large");
  pad_ = static_cast<int>(margin);
  stride_ = static_cast<int>(stride);
  rows_ = static_cast<int>(rows);
  const size_t cells = static_cast<size_t>(stride_) * static_cast<size_t>(rows_);
  std::vector<uint8_t> below(cells, outside_q_);  // level 0
  for (int y = 0; y < raster_.height; ++y)
    for (int x = 0; x < raster_.width; ++x) below[static_cast<size_t>(index(x, y))] = quantiseUp(raster_.at(x, y));
  levels_.push_back(below);
  // Level h from level h−1: a 2^h window is two 2^(h−1) windows half a window
  // apart, first along x, then along y, so each level costs O(cells). Cells
  // past the layout's edge are off the raster: outside_q.
  for (int h = 1; h < options_.branch_levels; ++h) {
    const int half = 1 << (h - 1);
    std::vector<uint8_t> along_x(cells);
    for (int sy = 0; sy < rows_; ++sy)
      for (int sx = 0; sx < stride_; ++sx) {
        const size_t i = static_cast<size_t>(sy) * static_cast<size_t>(stride_) + static_cast<size_t>(sx);
        along_x[i] = std::max(below[i], sx + half < stride_ ? below[i + static_cast<size_t>(half)] : outside_q_);
      }
    const size_t up = static_cast<size_t>(half) * static_cast<size_t>(stride_);
    for (int sy = 0; sy < rows_; ++sy)
      for (int sx = 0; sx < stride_; ++sx) {
        const size_t i = static_cast<size_t>(sy) * static_cast<size_t>(stride_) + static_cast<size_t>(sx);
        below[i] = std::max(along_x[i], sy + half < rows_ ? along_x[i + up] : outside_q_);
      }
    levels_.push_back(below);
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
  const int reach = lattice.linear_steps;                      // block starts within ±reach cells
  const int extent = (1 << (options_.branch_levels - 1)) - 1;  // a block's last cell past its start
  auto offRaster = [&](int v, int size) { return v + reach + extent < 0 || v - reach >= size; };
  auto inLayout = [&](int v, int size) { return v - reach >= -pad_ && v + reach < size + pad_; };
  std::vector<Rotation> rotations;
  rotations.reserve(static_cast<size_t>(2 * lattice.angular_steps + 1));
  for (int k = -lattice.angular_steps; k <= lattice.angular_steps; ++k) {
    Rotation rotation;
    rotation.theta_rad = center.theta_rad + k * lattice.angular_step_rad;
    // Pose2{centre, θ_k} * p with its cosine and sine computed once per rotation
    // (the same arithmetic, so the cells are those the lattice defines).
    const double c = std::cos(rotation.theta_rad), s = std::sin(rotation.theta_rad);
    rotation.cells.resize(points_robot.size());
    for (size_t i = 0; i < points_robot.size(); ++i) {
      const Eigen::Vector2d& p = points_robot[i];
      rotation.cells[i] = raster_.cellOf({center.x_m + c * p.x() - s * p.y(), center.y_m + s * p.x() + c * p.y()});
    }
    if (!levels_.empty()) {
      rotation.fast.resize(rotation.cells.size());
      size_t fast = 0;
      for (const Eigen::Vector2i& cell : rotation.cells) {
        if (offRaster(cell.x(), raster_.width) || offRaster(cell.y(), raster_.height))
          rotation.outside_sum += outside_q_;
        else if (inLayout(cell.x(), raster_.width) && inLayout(cell.y(), raster_.height))
          rotation.fast[fast++] = static_cast<int32_t>(index(cell.x(), cell.y()));
        else
          rotation.slow.push_back(cell);
      }
      rotation.fast.resize(fast);
    }
    rotations.push_back(std::move(rotation));
  }
  return rotations;
}

double CorrelativeMatcher::scoreAt(const Rotation& rotation, int dx, int dy) const {
  double sum = 0.0;
  for (const Eigen::Vector2i& c : rotation.cells) sum += raster_.at(c.x() + dx, c.y() + dy);
  return sum / static_cast<double>(rotation.cells.size());
}

uint32_t CorrelativeMatcher::boundAt(int h, const Rotation& rotation, int dx, int dy, uint32_t need) const {
  const uint8_t* v = levels_[static_cast<size_t>(h)].data();
  uint32_t sum = rotation.outside_sum;
  for (const Eigen::Vector2i& c : rotation.slow) {
    const auto sx = static_cast<unsigned>(c.x() + dx + pad_), sy = static_cast<unsigned>(c.y() + dy + pad_);
    sum += sx < static_cast<unsigned>(stride_) && sy < static_cast<unsigned>(rows_)
               ? v[static_cast<size_t>(sy) * static_cast<size_t>(stride_) + sx]
               : outside_q_;
  }
  const ptrdiff_t shift = static_cast<ptrdiff_t>(dy) * stride_ + dx;
  const int32_t* fast = rotation.fast.data();
  const size_t n = rotation.fast.size();
  constexpr size_t kChunk = 16;
  size_t i = 0;
  for (; i + kChunk <= n; i += kChunk) {
    uint32_t chunk = 0;
    for (size_t j = 0; j < kChunk; ++j) chunk += v[fast[i + j] + shift];
    sum += chunk;
    // Give up once even sure walls at every remaining point could not reach `need`.
    if (sum + 255u * static_cast<uint32_t>(n - i - kChunk) < need) return sum;
  }
  for (; i < n; ++i) sum += v[fast[i] + shift];
  return sum;
}

std::vector<CorrelativeMatcher::RotationGroup> CorrelativeMatcher::group(const std::vector<Rotation>& rotations,
                                                                          int size, int top, int reach) const {
  const int block = 1 << top;
  const int extent = (1 << (options_.branch_levels - 1)) - 1;
  const size_t n = rotations.front().cells.size();
  std::vector<RotationGroup> groups;
  for (int first = 0; first < static_cast<int>(rotations.size()); first += size) {
    RotationGroup g;
    g.first = first;
    g.count = std::min(size, static_cast<int>(rotations.size()) - first);
    std::vector<Eigen::Vector2i> lo(rotations[static_cast<size_t>(first)].cells), hi(lo);
    for (int r = first + 1; r < first + g.count; ++r) {
      const std::vector<Eigen::Vector2i>& cells = rotations[static_cast<size_t>(r)].cells;
      for (size_t i = 0; i < n; ++i) {
        lo[i] = lo[i].cwiseMin(cells[i]);
        hi[i] = hi[i].cwiseMax(cells[i]);
      }
    }
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector2i span = hi[i] - lo[i];
      if (span.x() > block || span.y() > block) {
        g.fixed_sum += 255;  // the two-window union would miss cells: bound by a sure wall
      } else if (hi[i].x() + reach + extent < 0 || lo[i].x() - reach >= raster_.width ||
                 hi[i].y() + reach + extent < 0 || lo[i].y() - reach >= raster_.height) {
        g.fixed_sum += outside_q_;
      } else if (lo[i].x() - reach >= -pad_ && hi[i].x() + reach < raster_.width + pad_ &&
                 lo[i].y() - reach >= -pad_ && hi[i].y() + reach < raster_.height + pad_) {
        g.fast.push_back(static_cast<int32_t>(index(lo[i].x(), lo[i].y())));
        g.right.push_back(span.x());
        g.up.push_back(span.y() * stride_);
      } else {
        g.slow.emplace_back(lo[i].x(), lo[i].y(), span.x(), span.y());
      }
    }
    groups.push_back(std::move(g));
  }
  return groups;
}

uint32_t CorrelativeMatcher::groupBoundAt(int h, const RotationGroup& group, int dx, int dy, uint32_t need) const {
  const uint8_t* v = levels_[static_cast<size_t>(h)].data();
  auto at = [&](int x, int y) {
    const auto sx = static_cast<unsigned>(x + pad_), sy = static_cast<unsigned>(y + pad_);
    return sx < static_cast<unsigned>(stride_) && sy < static_cast<unsigned>(rows_)
               ? v[static_cast<size_t>(sy) * static_cast<size_t>(stride_) + sx]
               : outside_q_;
  };
  uint32_t sum = group.fixed_sum;
  for (const Eigen::Vector4i& b : group.slow) {
    const int x = b[0] + dx, y = b[1] + dy;
    sum += std::max({at(x, y), at(x + b[2], y), at(x, y + b[3]), at(x + b[2], y + b[3])});
  }
  const ptrdiff_t shift = static_cast<ptrdiff_t>(dy) * stride_ + dx;
  const size_t n = group.fast.size();
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* corner = v + (group.fast[i] + shift);
    const int32_t right = group.right[i], up = group.up[i];
    sum += std::max(std::max(corner[0], corner[right]), std::max(corner[up], corner[up + right]));
    if ((i & 15) == 15 && sum + 255u * static_cast<uint32_t>(n - 1 - i) < need) return sum;
  }
  return sum;
}

uint32_t CorrelativeMatcher::needFor(double score, size_t points) {
  // The least quantised sum whose block may hold `score`, rounded down a
  // little so float rounding never prunes a block that holds it.
  return static_cast<uint32_t>(std::max(0.0, std::ceil(score * kQuanta * static_cast<double>(points) - 1e-6)));
}

void CorrelativeMatcher::descend(const std::vector<Rotation>& rotations, const Candidate& block, int linear_steps,
                                 double min_score, const Restriction& restriction, std::optional<Candidate>& best) const {
  const Rotation& rotation = rotations[static_cast<size_t>(block.rotation)];
  const size_t n = rotation.cells.size();
  const int level = block.level - 1;
  const int step = 1 << level;
  const uint32_t need_min = needFor(min_score, n);
  Candidate children[4];
  int count = 0;
  for (int dy = block.dy; dy <= block.dy + step && dy <= linear_steps; dy += step)
    for (int dx = block.dx; dx <= block.dx + step && dx <= linear_steps; dx += step) {
      if (restriction.done(best)) return;
      if (restriction.excludesBlock(dx, dy, level)) continue;
      if (level == 0) {  // a lattice pose: its exact score, when its quantised one may reach
        const uint32_t need = best ? std::max(need_min, needFor(best->score, n)) : need_min;
        if (boundAt(0, rotation, dx, dy, need) < need) continue;
        const double score = scoreAt(rotation, dx, dy);
        if (score >= min_score && (!best || score > best->score)) best = Candidate{block.rotation, dx, dy, 0, score};
        continue;
      }
      const uint32_t need = best ? std::max(need_min, needFor(best->score, n)) : need_min;
      const uint32_t sum = boundAt(level, rotation, dx, dy, need);
      if (sum < need) continue;
      const Candidate child{block.rotation, dx, dy, level, static_cast<double>(sum)};
      int at = count++;  // insertion keeps the (at most four) children sorted, best bound first
      for (; at > 0 && children[at - 1].score < child.score; --at) children[at] = children[at - 1];
      children[at] = child;
    }
  for (int i = 0; i < count; ++i) {
    if (restriction.done(best) || (best && children[i].score < needFor(best->score, n))) break;
    descend(rotations, children[i], linear_steps, min_score, restriction, best);
  }
}

std::optional<CorrelativeMatch> CorrelativeMatcher::match(std::span<const Eigen::Vector2d> points_robot,
                                                          const Pose2& center, double window_m, double window_rad,
                                                          double min_score,
                                                          const std::optional<ExcludedDisk>& excluded) const {
  return search(points_robot, center, window_m, window_rad, min_score, excluded, false);
}

std::optional<CorrelativeMatch> CorrelativeMatcher::firstAtLeast(std::span<const Eigen::Vector2d> points_robot,
                                                                 const Pose2& center, double window_m,
                                                                 double window_rad, double min_score,
                                                                 const std::optional<ExcludedDisk>& excluded) const {
  return search(points_robot, center, window_m, window_rad, min_score, excluded, true);
}

std::optional<CorrelativeMatch> CorrelativeMatcher::search(std::span<const Eigen::Vector2d> points_robot,
                                                           const Pose2& center, double window_m, double window_rad,
                                                           double min_score, const std::optional<ExcludedDisk>& excluded,
                                                           bool first_only) const {
  const SearchLattice lattice = this->lattice(points_robot, window_m, window_rad);
  if (!(min_score >= 0.0 && min_score <= 1.0))
    throw std::invalid_argument("correlative matcher: min_score must be in [0, 1], got " + std::to_string(min_score));
  if (!center.isFinite()) throw std::invalid_argument("correlative matcher: the centre pose is not finite");
  if (excluded && (!excluded->center_m.allFinite() || !(excluded->radius_m >= 0.0) || !std::isfinite(excluded->radius_m)))
    throw std::invalid_argument("correlative matcher: the excluded disk needs a finite centre and radius ≥ 0");
  for (const Eigen::Vector2d& p : points_robot)
    if (!p.allFinite()) throw std::invalid_argument("correlative matcher: a point is not finite");
  if (points_robot.empty()) return std::nullopt;
  const int64_t point_rotations = static_cast<int64_t>(points_robot.size()) * (2 * int64_t{lattice.angular_steps} + 1);
  if (point_rotations > kMaxPointRotations)
    throw std::invalid_argument("correlative matcher: " + std::to_string(points_robot.size()) + " points × " +
                                std::to_string(2 * lattice.angular_steps + 1) + " rotations is over " +
                                std::to_string(kMaxPointRotations) + "; subsample the points or set angular_step_rad");

  const std::vector<Rotation> rotations = discretise(points_robot, center, lattice);
  const int linear_steps = lattice.linear_steps;
  Restriction restriction;
  restriction.first_only = first_only;
  if (excluded) {
    const double r = raster_.resolution_m;
    restriction.disk = true;
    restriction.x = (excluded->center_m.x() - center.x_m) / r;
    restriction.y = (excluded->center_m.y() - center.y_m) / r;
    restriction.radius2 = std::pow(excluded->radius_m / r, 2);
  }
  std::optional<Candidate> best;
  // The coarsest level worth using: one block spanning the whole window.
  int top = 0;
  while (top + 1 < options_.branch_levels && (1 << top) < 2 * linear_steps + 1) ++top;
  if (top == 0) {  // no pooled level: brute force
    for (int r = 0; r < static_cast<int>(rotations.size()); ++r)
      for (int dy = -linear_steps; dy <= linear_steps; ++dy)
        for (int dx = -linear_steps; dx <= linear_steps; ++dx) {
          if (restriction.done(best)) break;
          if (restriction.excludes(dx, dy)) continue;
          const double score = scoreAt(rotations[static_cast<size_t>(r)], dx, dy);
          if (score >= min_score && (!best || score > best->score)) best = Candidate{r, dx, dy, 0, score};
        }
  } else {
    const int step = 1 << top;
    const size_t n = points_robot.size();
    const uint32_t need_min = needFor(min_score, n);
    auto byBound = [](const Candidate& a, const Candidate& b) { return a.score > b.score; };
    // Top blocks of single rotations, searched best bound first.
    auto searchTop = [&](std::vector<Candidate>& candidates) {
      std::stable_sort(candidates.begin(), candidates.end(), byBound);
      for (const Candidate& c : candidates) {
        if (restriction.done(best) || (best && c.score < needFor(best->score, n))) break;
        descend(rotations, c, linear_steps, min_score, restriction, best);
      }
    };
    // A group of rotations moves the farthest point by about one cell per
    // rotation: half a top block widens the bound little (measured: groups of
    // 2^(top−1) and 2^top about equal, 2^(top−2) 10 % and 2^(top−3) 25 % slower).
    const int group_size = top >= 2 ? 1 << (top - 1) : 1;
    if (group_size > 1 && static_cast<int>(rotations.size()) >= 2 * group_size) {
      const std::vector<RotationGroup> groups = group(rotations, group_size, top, linear_steps);
      std::vector<Candidate> blocks;  // `rotation` indexes groups here
      for (int dy = -linear_steps; dy <= linear_steps; dy += step)
        for (int dx = -linear_steps; dx <= linear_steps; dx += step)
          for (int g = 0; g < static_cast<int>(groups.size()); ++g) {
            const uint32_t sum = groupBoundAt(top, groups[static_cast<size_t>(g)], dx, dy, need_min);
            if (sum >= need_min) blocks.push_back({g, dx, dy, top, static_cast<double>(sum)});
          }
      std::stable_sort(blocks.begin(), blocks.end(), byBound);
      std::vector<Candidate> members;
      for (const Candidate& b : blocks) {
        const uint32_t need = best ? std::max(need_min, needFor(best->score, n)) : need_min;
        if (b.score < need || restriction.done(best)) break;
        const RotationGroup& g = groups[static_cast<size_t>(b.rotation)];
        members.clear();
        for (int r = g.first; r < g.first + g.count; ++r) {
          const uint32_t sum = boundAt(top, rotations[static_cast<size_t>(r)], b.dx, b.dy, need);
          if (sum >= need) members.push_back({r, b.dx, b.dy, top, static_cast<double>(sum)});
        }
        searchTop(members);
      }
    } else {
      std::vector<Candidate> candidates;
      // Rotations innermost: neighbouring rotations move each point by at most a
      // cell, so they read the same cache lines.
      for (int dy = -linear_steps; dy <= linear_steps; dy += step)
        for (int dx = -linear_steps; dx <= linear_steps; dx += step)
          for (int r = 0; r < static_cast<int>(rotations.size()); ++r) {
            const uint32_t sum = boundAt(top, rotations[static_cast<size_t>(r)], dx, dy, need_min);
            if (sum >= need_min) candidates.push_back({r, dx, dy, top, static_cast<double>(sum)});
          }
      searchTop(candidates);
    }
  }
  if (!best) return std::nullopt;
  const double r = raster_.resolution_m;
  return CorrelativeMatch{{center.x_m + best->dx * r, center.y_m + best->dy * r,
                           normalizeAngle(rotations[static_cast<size_t>(best->rotation)].theta_rad)},
                          best->score};
}

}  // namespace rmap::slam2d
