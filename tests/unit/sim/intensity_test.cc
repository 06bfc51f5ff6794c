#include "sim/intensity.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

namespace rmap::sim {
namespace {

TEST(Intensity, FollowsTheDocumentedFormula) {
  IntensityModel m;
  m.saturation = 1e9;
  const double r = 5.0, c = 0.8;
  const double near = 1.0 - std::exp(-std::pow(r / m.near_range_m, m.near_exponent));
  EXPECT_DOUBLE_EQ(m.expected(0.5, r, c), m.gain * 0.5 * std::pow(c, m.incidence_exponent) * near / std::pow(r, m.range_exponent));
  EXPECT_EQ(m.expected(0.5, 0.0, 1.0), 0.0);
}

TEST(Intensity, ShapeOfTheResponse) {
  const IntensityModel m;
  // Proportional to reflectivity (below saturation).
  EXPECT_NEAR(m.expected(0.8, 6.0, 1.0) / m.expected(0.2, 6.0, 1.0), 4.0, 1e-12);
  // Falls with range beyond the near zone, with the model's exponent rather than 2.
  EXPECT_GT(m.expected(0.5, 4.0, 1.0), m.expected(0.5, 8.0, 1.0));
  EXPECT_NEAR(m.expected(0.5, 10.0, 1.0) / m.expected(0.5, 20.0, 1.0), std::pow(2.0, m.range_exponent), 1e-6);
  // Drops again close to the sensor.
  EXPECT_LT(m.expected(0.5, 0.5, 1.0), m.expected(0.5, 1.0, 1.0));
  EXPECT_LT(m.expected(0.5, 1.0, 1.0), m.expected(0.5, 1.5, 1.0));
  // Falls with incidence angle.
  EXPECT_GT(m.expected(0.5, 5.0, 1.0), m.expected(0.5, 5.0, std::cos(0.5)));
  EXPECT_GT(m.expected(0.5, 5.0, std::cos(0.5)), m.expected(0.5, 5.0, std::cos(1.2)));
  // Saturates.
  IntensityModel hot = m;
  hot.gain = 1e5;
  EXPECT_EQ(hot.expected(1.0, 3.0, 1.0), hot.saturation);
}

TEST(Intensity, MultiplicativeNoiseHasTheConfiguredSpread) {
  IntensityModel m;
  m.noise_rel_sigma = 0.05;
  std::mt19937_64 rng(1);
  const double mean = m.expected(0.5, 6.0, 1.0);
  double sum = 0, sum2 = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const double rel = m.sample(0.5, 6.0, 1.0, rng) / mean - 1.0;
    sum += rel;
    sum2 += rel * rel;
  }
  EXPECT_NEAR(sum / n, 0.0, 0.002);
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.05, 0.002);
}

TEST(Intensity, ValidateNamesBadParameters) {
  IntensityModel m;
  m.range_exponent = 0.0;
  EXPECT_THROW(m.validate(), std::invalid_argument);
  m = IntensityModel{};
  m.noise_rel_sigma = -1.0;
  EXPECT_THROW(m.validate(), std::invalid_argument);
  EXPECT_NO_THROW(IntensityModel{}.validate());
}

}  // namespace
}  // namespace rmap::sim
