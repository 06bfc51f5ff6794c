#include "slam2d/occupancy_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rmap::slam2d {

OccupancyGrid::OccupancyGrid(double resolution_m) : resolution_m_(resolution_m), inv_resolution_(1.0 / resolution_m) {
  if (!(resolution_m > 0.0) || !std::isfinite(resolution_m))
    throw std::invalid_argument("OccupancyGrid: resolution_m must be positive and finite");
}

Eigen::Vector2i OccupancyGrid::cellOf(const Eigen::Vector2d& p_m) const {
  return {static_cast<int>(std::floor(p_m.x() * inv_resolution_)),
          static_cast<int>(std::floor(p_m.y() * inv_resolution_))};
}

float OccupancyGrid::logOdds(const Eigen::Vector2i& cell) const {
  const Cell* c = cells_.find(cell.x(), cell.y());
  return c ? c->log_odds : std::numeric_limits<float>::quiet_NaN();
}

float OccupancyGrid::probability(const Eigen::Vector2i& cell) const {
  const float l = logOdds(cell);
  return std::isnan(l) ? l : 1.0f / (1.0f + std::exp(-l));
}

OccupancyGrid::Sample OccupancyGrid::sample(const Eigen::Vector2d& p_m) const {
  // Cell values sit at cell centres: shift by half a cell before flooring.
  const double u = p_m.x() * inv_resolution_ - 0.5, v = p_m.y() * inv_resolution_ - 0.5;
  const double fu = std::floor(u), fv = std::floor(v);
  const int x = static_cast<int>(fu), y = static_cast<int>(fv);
  const float ax = static_cast<float>(u - fu), ay = static_cast<float>(v - fv);
  float v00, v10, v01, v11;
  constexpr int kMask = ChunkedGrid<Cell>::kChunkMask;
  if ((x & kMask) != kMask && (y & kMask) != kMask) {
    // All four cells share one chunk: one lookup.
    const Cell* c = cells_.find(x, y);
    if (!c) return {};
    constexpr int kEdge = ChunkedGrid<Cell>::kChunkEdge;
    v00 = c[0].value, v10 = c[1].value, v01 = c[kEdge].value, v11 = c[kEdge + 1].value;
  } else {
    v00 = value(x, y), v10 = value(x + 1, y), v01 = value(x, y + 1), v11 = value(x + 1, y + 1);
  }
  Sample s;
  s.value = (1.0f - ay) * ((1.0f - ax) * v00 + ax * v10) + ay * ((1.0f - ax) * v01 + ax * v11);
  const float inv_res = static_cast<float>(inv_resolution_);
  s.gradient_per_m.x() = ((1.0f - ay) * (v10 - v00) + ay * (v11 - v01)) * inv_res;
  s.gradient_per_m.y() = ((1.0f - ax) * (v01 - v00) + ax * (v11 - v10)) * inv_res;
  return s;
}

// Inlined into miss() and hit(), so into the ray walk (raw fr079 with loop closure −4.6 % CPU, BENCHMARKS §4).
[[gnu::always_inline]] inline void OccupancyGrid::apply(Cell& cell, float delta, const OccupancyUpdate& update, int x,
                                                        int y) {
  const bool known = !std::isnan(cell.log_odds);
  if (!known) {
    cell.log_odds = 0.0f;
    known_.extend(Eigen::Vector2i(x, y));
  }
  const float log_odds = std::clamp(cell.log_odds + delta, update.min_log_odds, update.max_log_odds);
  // A known cell at a clamp bound stays there (most free cells, once mapped): its value holds it.
  if (known && log_odds == cell.log_odds) return;
  cell.log_odds = log_odds;
  const float p = 1.0f / (1.0f + std::exp(-log_odds));
  cell.value = std::max(0.0f, (p - update.value_floor_probability) / (1.0f - update.value_floor_probability));
}

// Inlined into the ray walk, which calls it for every crossed cell: as a call it cost
// a fifth of raw fr079's run with loop closure (BENCHMARKS §4, *Ray walk*).
[[gnu::always_inline]] inline void OccupancyGrid::miss(int x, int y, const OccupancyUpdate& update, Cursor& cursor) {
  Cell& cell = cells_.at(x, y, cursor);
  if ((cell.mark >> 1) == insertion_) return;  // already changed by this scan
  cell.mark = insertion_ << 1;
  apply(cell, update.miss_log_odds, update, x, y);
}

void OccupancyGrid::hit(int x, int y, const OccupancyUpdate& update, Cursor& cursor) {
  Cell& cell = cells_.at(x, y, cursor);
  const uint32_t hit_mark = (insertion_ << 1) | 1u;
  if (cell.mark == hit_mark) return;
  // A beam of this scan crossed the cell before another ended in it: the hit wins.
  const float undo = (cell.mark == insertion_ << 1) ? -update.miss_log_odds : 0.0f;
  cell.mark = hit_mark;
  apply(cell, undo + update.hit_log_odds, update, x, y);
}

void OccupancyGrid::insert(const Eigen::Vector2d& origin_m, std::span<const Ray> rays, const OccupancyUpdate& update,
                           double max_ray_m) {
  ++insertion_;  // marks of earlier scans never equal the new ones (wraps after 2^31 scans)
  if (insertion_ >= (1u << 31)) insertion_ = 1;
  const double ox = origin_m.x() * inv_resolution_, oy = origin_m.y() * inv_resolution_;
  Cursor cursor;
  for (const Ray& ray : rays) {
    Eigen::Vector2d end = ray.end_m;
    bool is_hit = ray.hit;
    const double length = (end - origin_m).norm();
    if (length > max_ray_m) {
      end = origin_m + (end - origin_m) * (max_ray_m / length);
      is_hit = false;
    }
    const double ex = end.x() * inv_resolution_, ey = end.y() * inv_resolution_;
    // Amanatides–Woo walk through the cells from the origin's to the end's.
    int x = static_cast<int>(std::floor(ox)), y = static_cast<int>(std::floor(oy));
    const int end_x = static_cast<int>(std::floor(ex)), end_y = static_cast<int>(std::floor(ey));
    const double dx = ex - ox, dy = ey - oy;
    const int step_x = dx > 0 ? 1 : -1, step_y = dy > 0 ? 1 : -1;
    const double t_dx = dx != 0.0 ? std::abs(1.0 / dx) : INFINITY;
    const double t_dy = dy != 0.0 ? std::abs(1.0 / dy) : INFINITY;
    double t_x = dx != 0.0 ? ((dx > 0 ? (x + 1 - ox) : (ox - x)) * t_dx) : INFINITY;
    double t_y = dy != 0.0 ? ((dy > 0 ? (y + 1 - oy) : (oy - y)) * t_dy) : INFINITY;
    const bool steps_walked = update.miss_log_odds != 0.0f;
    int steps = steps_walked ? std::abs(end_x - x) + std::abs(end_y - y) : 0;
    for (; steps > 0; --steps) {
      miss(x, y, update, cursor);
      if (t_x < t_y) {
        x += step_x;
        t_x += t_dx;
      } else {
        y += step_y;
        t_y += t_dy;
      }
    }
    if (is_hit)
      hit(end_x, end_y, update, cursor);
    else if (steps_walked)
      miss(end_x, end_y, update, cursor);
  }
}

}  // namespace rmap::slam2d
