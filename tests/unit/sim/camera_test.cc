#include "sim/camera.h"

#include "test_worlds.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace rmap::sim {
namespace {

using test::at;

/// A closed room of reflectivity 0.5 whose +x wall is 0.9 on its left half (y > 0).
VoxelWorld litRoom() {
  VoxelWorld w = test::closedRoom(4.0, 0.5f);
  w.fillBox(box(5, 0, 0, 5.3, 5, 4), 0.9f);
  return w;
}

Lighting noiseless(double level) {
  Lighting l;
  l.light_level = level;
  l.noise_sigma = 0.0;
  l.light_direction = Eigen::Vector3d(1, 0, 0);  // light travels +x: lights faces whose normal points −x fully
  return l;
}

CameraModel fixedExposure() {
  CameraModel m;
  m.width_px = 64;
  m.height_px = 48;
  m.auto_exposure = false;
  return m;
}

TEST(Camera, RendersReflectivityTimesLight) {
  std::mt19937_64 rng(1);
  const CameraModel m = fixedExposure();
  const GreyImage img = renderCamera(litRoom(), at(0, 0, 2), m, noiseless(1.0), rng);
  ASSERT_EQ(img.width, 64);
  ASSERT_EQ(img.pixels.size(), 64u * 48u);
  // The facing wall's normal is −x, against the light: full light.
  EXPECT_EQ(img.at(16, 24), 230);  // left half (y > 0): 255 · 0.9
  EXPECT_EQ(img.at(48, 24), 128);  // right half: 255 · 0.5, rounded
  // Half the light halves the grey values.
  const GreyImage dim = renderCamera(litRoom(), at(0, 0, 2), m, noiseless(0.5), rng);
  EXPECT_EQ(dim.at(16, 24), 115);
  // The floor (normal +z, perpendicular to the light) gets the ambient share only.
  EXPECT_EQ(img.at(32, 47), std::lround(255 * 0.5 * 0.4));
}

TEST(Camera, AutoExposureEvensOutTheLightLevelUntilTheGainRunsOut) {
  std::mt19937_64 rng(3);
  CameraModel m = fixedExposure();
  m.auto_exposure = true;
  m.target_mean_grey = 100.0;
  const GreyImage day = renderCamera(litRoom(), at(0, 0, 2), m, noiseless(1.0), rng);
  const GreyImage dusk = renderCamera(litRoom(), at(0, 0, 2), m, noiseless(0.25), rng);
  auto mean = [](const GreyImage& g) {
    double s = 0.0;
    for (uint8_t p : g.pixels) s += p;
    return s / g.pixels.size();
  };
  EXPECT_NEAR(mean(day), 100.0, 2.0);
  EXPECT_NEAR(mean(dusk), 100.0, 2.0);
  EXPECT_NEAR(dusk.at(16, 24), day.at(16, 24), 1);
  // At 1 % light the gain stops at max_auto_gain (16).
  const double fixed_day = mean(renderCamera(litRoom(), at(0, 0, 2), fixedExposure(), noiseless(1.0), rng));
  const GreyImage night = renderCamera(litRoom(), at(0, 0, 2), m, noiseless(0.01), rng);
  EXPECT_NEAR(mean(night), 0.01 * m.max_auto_gain * fixed_day, 1.0);
}

TEST(Camera, DarkLeavesOnlyNoise) {
  std::mt19937_64 rng(2);
  const CameraModel m = fixedExposure();
  Lighting dark = noiseless(0.0);
  dark.noise_sigma = 3.0;
  const GreyImage img = renderCamera(litRoom(), at(0, 0, 2), m, dark, rng);
  double sum = 0.0;
  for (uint8_t g : img.pixels) sum += g;
  EXPECT_LT(sum / img.pixels.size(), 2.0);  // half the noise clamps at 0: mean ≈ σ/√(2π)
  EXPECT_GT(sum, 0.0);
}

TEST(Camera, SameSeedSameImage) {
  CameraModel m;
  m.width_px = 32;
  m.height_px = 32;
  std::mt19937_64 a(5), b(5);
  EXPECT_EQ(renderCamera(litRoom(), at(1, 1, 2, 0.3), m, {}, a).pixels, renderCamera(litRoom(), at(1, 1, 2, 0.3), m, {}, b).pixels);
}

TEST(Camera, BadModelOrLightingThrows) {
  std::mt19937_64 rng(1);
  CameraModel m;
  m.width_px = 2;
  EXPECT_THROW(renderCamera(litRoom(), at(0, 0, 2), m, {}, rng), std::invalid_argument);
  Lighting l;
  l.light_level = -1.0;
  EXPECT_THROW(renderCamera(litRoom(), at(0, 0, 2), {}, l, rng), std::invalid_argument);
  l = {};
  l.light_direction = Eigen::Vector3d::Zero();
  EXPECT_THROW(renderCamera(litRoom(), at(0, 0, 2), {}, l, rng), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::sim
