#include "slam2d/reflectivity_layer.h"

#include <gtest/gtest.h>

#include <cmath>

namespace rmap::slam2d {
namespace {

TEST(ReflectivityLayer, FusesMeanAndSpread) {
  ReflectivityLayer layer(0.05);
  EXPECT_EQ(layer.at({3, 4}).count, 0u);
  for (float r : {0.2f, 0.4f, 0.6f, 0.8f}) layer.add({3, 4}, r);
  const ReflectivityCell c = layer.at({3, 4});
  EXPECT_EQ(c.count, 4u);
  EXPECT_NEAR(c.mean, 0.5f, 1e-6);
  EXPECT_NEAR(c.stddev, std::sqrt(0.05f), 1e-6);  // population spread of 0.2..0.8
  EXPECT_EQ(layer.at({3, 5}).count, 0u);
  layer.add({-1000, 2000}, 0.9f);
  EXPECT_EQ(layer.at({-1000, 2000}).count, 1u);
  EXPECT_EQ(layer.at({-1000, 2000}).stddev, 0.0f);
}

TEST(ReflectivityLayer, InterpolatesOverCellsWithReflectivityOnly) {
  ReflectivityLayer layer(1.0);
  layer.add({0, 0}, 0.2f);
  layer.add({1, 0}, 0.8f);
  // Between the two centres: linear, slope 0.6 per metre.
  const ReflectivityLayer::Sample mid = layer.sample({1.0, 0.5});
  EXPECT_NEAR(mid.value, 0.5f, 1e-6);
  EXPECT_NEAR(mid.gradient_per_m.x(), 0.6f, 1e-5);
  EXPECT_NEAR(mid.gradient_per_m.y(), 0.0f, 1e-5);
  EXPECT_NEAR(mid.support, 1.0f, 1e-6);
  // Towards the empty row above, the value stays that of the wall (no fall to 0).
  const ReflectivityLayer::Sample up = layer.sample({0.5, 1.2});
  EXPECT_NEAR(up.value, 0.2f, 1e-6);
  EXPECT_NEAR(up.support, 0.3f, 1e-5);
  EXPECT_EQ(layer.sample({10.0, 10.0}).support, 0.0f);
}

}  // namespace
}  // namespace rmap::slam2d
