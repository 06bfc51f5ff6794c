#include "slam2d/reflectivity_layer.h"

#include <cmath>

namespace rmap::slam2d {

ReflectivityLayer::ReflectivityLayer(double resolution_m) : inv_resolution_(1.0 / resolution_m) {}

ReflectivityCell ReflectivityLayer::at(const Eigen::Vector2i& cell) const {
  const Cell* c = cells_.find(cell.x(), cell.y());
  if (!c || c->count == 0) return {};
  return {c->mean, std::sqrt(std::max(0.0f, c->m2 / static_cast<float>(c->count))), c->count};
}

void ReflectivityLayer::add(const Eigen::Vector2i& cell, float reflectivity) {
  Cell& c = cells_.at(cell.x(), cell.y());
  ++c.count;
  const float delta = reflectivity - c.mean;
  c.mean += delta / static_cast<float>(c.count);
  c.m2 += delta * (reflectivity - c.mean);
}

ReflectivityLayer::Sample ReflectivityLayer::sample(const Eigen::Vector2d& p_m) const {
  const double u = p_m.x() * inv_resolution_ - 0.5, v = p_m.y() * inv_resolution_ - 0.5;
  const double fu = std::floor(u), fv = std::floor(v);
  const int x = static_cast<int>(fu), y = static_cast<int>(fv);
  const float ax = static_cast<float>(u - fu), ay = static_cast<float>(v - fv);
  // Weights w_k(ax, ay) and their derivatives for the corners 00, 10, 01, 11.
  const float w[4] = {(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay};
  const float dwx[4] = {-(1 - ay), 1 - ay, -ay, ay};
  const float dwy[4] = {-(1 - ax), -ax, 1 - ax, ax};
  const int cx[4] = {x, x + 1, x, x + 1}, cy[4] = {y, y, y + 1, y + 1};
  float num = 0, den = 0, dnum_x = 0, dnum_y = 0, dden_x = 0, dden_y = 0;
  for (int k = 0; k < 4; ++k) {
    const Cell* c = cells_.find(cx[k], cy[k]);
    if (!c || c->count == 0) continue;
    num += w[k] * c->mean, den += w[k];
    dnum_x += dwx[k] * c->mean, dnum_y += dwy[k] * c->mean;
    dden_x += dwx[k], dden_y += dwy[k];
  }
  Sample s;
  s.support = den;
  if (den <= 1e-6f) return s;
  s.value = num / den;
  // Quotient rule for num/den, then cells → metres.
  const float scale = static_cast<float>(inv_resolution_) / (den * den);
  s.gradient_per_m = {(dnum_x * den - num * dden_x) * scale, (dnum_y * den - num * dden_y) * scale};
  return s;
}

}  // namespace rmap::slam2d
