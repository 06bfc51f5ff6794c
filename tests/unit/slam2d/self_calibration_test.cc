#include "slam2d/self_calibration.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "angles.h"
#include "sim/laser2d.h"

namespace rmap::slam2d {
namespace {


/// Readings of `cells` surface cells of random reflectivity, each seen from
/// `views` random viewpoints (range log-uniform in [near_m, far_m], incidence up to 70°).
struct Survey {
  std::vector<float> reflectivity;  ///< per cell
  std::vector<IntensityObservation> readings;
};

Survey survey(const sim::IntensityModel& model, int cells, int views, uint64_t seed, double near_m = 0.3,
              double far_m = 12.0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> rho(0.05, 0.95), log_r(std::log(near_m), std::log(far_m)), alpha(0.0, 70 * kDeg);
  Survey s;
  for (int c = 0; c < cells; ++c) {
    s.reflectivity.push_back(float(rho(rng)));
    for (int v = 0; v < views; ++v) {
      const double r = std::exp(log_r(rng)), cos_a = std::cos(alpha(rng));
      s.readings.push_back({uint64_t(1000 + 7 * c), float(r), float(cos_a), float(model.sample(s.reflectivity[c], r, cos_a, rng))});
    }
  }
  return s;
}

std::vector<ReflectivityObservation> targets(const Survey& s) {
  std::vector<ReflectivityObservation> out;
  for (const IntensityObservation& o : s.readings) {
    out.push_back({s.reflectivity[(o.cell_id - 1000) / 7], o.range_m, o.cos_incidence, o.intensity});
  }
  return out;
}

struct Errors {
  double median_rel;  ///< |ρ̂ − ρ| / ρ over readings with a reflectivity
  double coverage;    ///< fraction of readings that got one
};

Errors errors(const IntensityCalibration& cal, const Survey& s) {
  std::vector<double> rel;
  for (const IntensityObservation& o : s.readings) {
    const double truth = s.reflectivity[(o.cell_id - 1000) / 7];
    const double rho = cal.reflectivity(o.intensity, o.range_m, o.cos_incidence);
    if (std::isfinite(rho)) rel.push_back(std::abs(rho - truth) / truth);
  }
  if (rel.empty()) return {1.0, 0.0};
  std::nth_element(rel.begin(), rel.begin() + rel.size() / 2, rel.end());
  return {rel[rel.size() / 2], double(rel.size()) / s.readings.size()};
}

class BothPresets : public ::testing::TestWithParam<bool> {
 protected:
  sim::IntensityModel model() const {
    return GetParam() ? sim::Laser2dModel::sickLike().intensity : sim::Laser2dModel::hokuyoLike().intensity;
  }
};

TEST_P(BothPresets, SupervisedFitRecoversReflectivityOnNewData) {
  const sim::IntensityModel m = model();
  const IntensityCalibration cal = fitCalibration(targets(survey(m, 300, 40, 1)));
  const Errors e = errors(cal, survey(m, 200, 30, 2));
  EXPECT_LT(e.median_rel, 1.2 * m.noise_rel_sigma);  // the noise floor: median |n|σ ≈ 0.67σ
  EXPECT_GT(e.coverage, 0.7);                        // saturated and near-blind readings drop out
  // The learned shape: a factor 4 farther loses 4^e.
  EXPECT_NEAR(std::log(cal.response(2.0, 1.0) / cal.response(8.0, 1.0)) / std::log(4.0), m.range_exponent, 0.05);
  EXPECT_NEAR(std::log(cal.response(5.0, std::cos(60 * kDeg)) / cal.response(5.0, 1.0)) / std::log(0.5),
              m.incidence_exponent, 0.05);
}

TEST_P(BothPresets, SelfCalibrationFindsTheShapeAndOneTargetTheScale) {
  const sim::IntensityModel m = model();
  const Survey map = survey(m, 400, 25, 3);
  const IntensityCalibration self = selfCalibrate(map.readings);
  // Normalisation: the median cell reads 0.5.
  std::vector<double> cell_mean;
  for (size_t c = 0; c < map.reflectivity.size(); ++c) {
    std::vector<double> v;
    for (size_t j = c * 25; j < (c + 1) * 25; ++j) {
      const IntensityObservation& o = map.readings[j];
      const double rho = self.reflectivity(o.intensity, o.range_m, o.cos_incidence);
      if (std::isfinite(rho)) v.push_back(rho);
    }
    if (v.size() < 3) continue;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    cell_mean.push_back(v[v.size() / 2]);
  }
  std::nth_element(cell_mean.begin(), cell_mean.begin() + cell_mean.size() / 2, cell_mean.end());
  EXPECT_NEAR(cell_mean[cell_mean.size() / 2], 0.5, 0.02);
  // One target of known ρ sets the absolute scale.
  std::vector<ReflectivityObservation> reference;
  std::mt19937_64 rng(4);
  for (double r = 1.0; r <= 6.0; r += 0.25) reference.push_back({0.7f, float(r), 0.95f, float(m.sample(0.7, r, 0.95, rng))});
  const IntensityCalibration anchored = self.anchoredTo(reference);
  const Errors e = errors(anchored, survey(m, 200, 30, 5));
  EXPECT_LT(e.median_rel, 2.0 * m.noise_rel_sigma);
  EXPECT_GT(e.coverage, 0.7);
}

INSTANTIATE_TEST_SUITE_P(Sim, BothPresets, ::testing::Values(true, false),
                         [](const auto& info) { return info.param ? "SickLike" : "HokuyoLike"; });

TEST(SelfCalibration, CellsThatMixTwoMaterialsDoNotBendTheResponse) {
  sim::IntensityModel m = sim::Laser2dModel::sickLike().intensity;
  Survey map = survey(m, 300, 25, 6);
  std::mt19937_64 rng(7);
  std::bernoulli_distribution mixed(0.08);
  for (IntensityObservation& o : map.readings) {
    if (mixed(rng)) o.intensity *= 0.25f;  // the beam ended on the neighbouring dark material
  }
  std::vector<ReflectivityObservation> reference;
  for (double r = 1.0; r <= 6.0; r += 0.25) reference.push_back({0.7f, float(r), 1.0f, float(m.expected(0.7, r, 1.0))});
  const Errors e = errors(selfCalibrate(map.readings).anchoredTo(reference), survey(m, 200, 30, 8));
  EXPECT_LT(e.median_rel, 0.03);
}

TEST(SelfCalibration, NeedsCellsSeenMoreThanOnce) {
  const Survey once = survey(sim::Laser2dModel::sickLike().intensity, 500, 1, 9);
  EXPECT_THROW(selfCalibrate(once.readings), std::invalid_argument);
  SelfCalibrationOptions o;
  o.min_views_per_cell = 1;
  EXPECT_THROW(selfCalibrate(once.readings, o), std::invalid_argument);
  EXPECT_THROW(fitCalibration({}), std::invalid_argument);
  CalibrationFitOptions bad;
  bad.range_knot_step = 0.0;
  EXPECT_THROW(fitCalibration(targets(once), bad), std::invalid_argument);
}

TEST(DetectSaturation, FindsTheClippedPileAndNothingElse) {
  std::mt19937_64 rng(10);
  std::uniform_real_distribution<double> raw(std::log(5.0), std::log(3000.0));
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<float> clipped_then_noisy, clipped_exactly, unclipped;
  for (int i = 0; i < 20000; ++i) {
    const double ideal = std::exp(raw(rng)), n = noise(rng);
    clipped_then_noisy.push_back(float(std::min(1000.0, ideal) * (1.0 + 0.03 * n)));
    clipped_exactly.push_back(float(std::min(1000.0, ideal * (1.0 + 0.03 * n))));
    unclipped.push_back(float(ideal * (1.0 + 0.03 * n)));
  }
  EXPECT_NEAR(detectSaturation(clipped_then_noisy), 1000.0 * (1.0 - 3 * 0.03), 25.0);
  const double exact = detectSaturation(clipped_exactly);
  EXPECT_LT(exact, 1000.0);
  EXPECT_GT(exact, 970.0);
  EXPECT_TRUE(std::isinf(detectSaturation(unclipped)));
  EXPECT_TRUE(std::isinf(detectSaturation({})));
}

TEST(SelfCalibration, BrightReadingsAtThePeakOfTheResponseAreNotSaturation) {
  // Hokuyo-like g peaks near 1.7 m: surveyed around there without clipping,
  // the top of the count range is crowded but no reading falls short of g.
  sim::IntensityModel m = sim::Laser2dModel::hokuyoLike().intensity;
  m.saturation = 1e9;
  const Survey map = survey(m, 300, 30, 13, 1.2, 2.5);
  EXPECT_TRUE(std::isinf(fitCalibration(targets(map)).saturation()));
  EXPECT_TRUE(std::isinf(selfCalibrate(map.readings).saturation()));
}

TEST(SelfCalibration, SaturatedReadingsAreLeftOutAndFlagged) {
  sim::IntensityModel m = sim::Laser2dModel::sickLike().intensity;
  const Survey map = survey(m, 300, 30, 11, 0.5, 4.0);  // close: bright cells clip within about 1.3 m
  const IntensityCalibration cal = fitCalibration(targets(map));
  EXPECT_LT(cal.saturation(), m.saturation);
  EXPECT_GT(cal.saturation(), m.saturation * (1.0 - 4.0 * m.noise_rel_sigma));
  EXPECT_TRUE(std::isnan(cal.reflectivity(m.saturation, 3.0, 1.0)));
  const Errors e = errors(cal, survey(m, 200, 30, 12, 0.5, 4.0));
  EXPECT_LT(e.median_rel, 1.2 * m.noise_rel_sigma);
}

}  // namespace
}  // namespace rmap::slam2d
