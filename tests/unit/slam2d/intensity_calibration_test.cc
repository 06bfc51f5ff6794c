#include "slam2d/intensity_calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "angles.h"

namespace rmap::slam2d {
namespace {


/// Spline whose coefficients sample f at the Greville abscissae lo + (k − 1)·h:
/// exact for linear f.
template <class F>
CubicBSpline linearSpline(double lo, double hi, int n, F f) {
  CubicBSpline s{lo, hi, {}};
  const double h = (hi - lo) / (n - 3);
  for (int k = 0; k < n; ++k) s.coefficients.push_back(f(lo + (k - 1) * h));
  return s;
}

/// g = 1000 · r⁻² · exp(−0.01 α/°) on r ∈ [0.5, 20] m, α ≤ 70°, saturating at 5000 counts.
IntensityCalibration inverseSquare() {
  return IntensityCalibration(linearSpline(std::log(0.5), std::log(20.0), 8, [](double x) { return std::log(1000.0) - 2.0 * x; }),
                              linearSpline(0.0, 70.0, 6, [](double a) { return -0.01 * a; }), 5000.0, 1.0);
}

void expectFromTextError(const std::string& text, const std::string& part) {
  try {
    IntensityCalibration::fromText(text);
    ADD_FAILURE() << "accepted:\n" << text;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

TEST(CubicBSpline, WeightsSumToOneAndLinesAreReproduced) {
  const CubicBSpline line = linearSpline(-1.0, 3.0, 9, [](double x) { return 2.0 - 0.5 * x; });
  for (double x = -1.0; x <= 3.0; x += 0.037) {
    std::array<double, 4> w;
    const int first = line.basis(x, w);
    EXPECT_GE(first, 0);
    EXPECT_LE(first + 3, 8);
    EXPECT_NEAR(w[0] + w[1] + w[2] + w[3], 1.0, 1e-12);
    EXPECT_NEAR(line(x), 2.0 - 0.5 * x, 1e-12) << x;
  }
  EXPECT_NEAR(line(10.0), line(3.0), 1e-12);  // clamped outside
  const CubicBSpline bump{0.0, 1.0, {0, 0, 0, 6, 0, 0, 0}};
  EXPECT_NEAR(bump(0.5), 4.0, 1e-12);  // centre of the middle coefficient's support: B₁(0)·6
}

TEST(IntensityCalibration, ResponseAndReflectivityFollowTheModel) {
  const IntensityCalibration cal = inverseSquare();
  EXPECT_NEAR(cal.minRange_m(), 0.5, 1e-12);
  EXPECT_NEAR(cal.maxRange_m(), 20.0, 1e-9);
  EXPECT_EQ(cal.maxIncidence_deg(), 70.0);
  EXPECT_NEAR(cal.response(2.0, 1.0), 250.0, 1e-9);
  EXPECT_NEAR(cal.response(10.0, std::cos(60 * kDeg)), 10.0 * std::exp(-0.6), 1e-9);
  EXPECT_NEAR(cal.reflectivity(125.0, 2.0, 1.0), 0.5, 1e-12);
  EXPECT_NEAR(cal.reflectivity(0.0, 2.0, 1.0), 0.0, 1e-12);
}

TEST(IntensityCalibration, ReflectivityIsNaNOutsideWhatWasLearned) {
  const IntensityCalibration cal = inverseSquare();
  EXPECT_TRUE(std::isnan(cal.reflectivity(100.0, 0.4, 1.0)));              // too close
  EXPECT_TRUE(std::isnan(cal.reflectivity(100.0, 25.0, 1.0)));             // too far
  EXPECT_TRUE(std::isnan(cal.reflectivity(100.0, 2.0, std::cos(75 * kDeg))));  // too oblique
  EXPECT_TRUE(std::isnan(cal.reflectivity(100.0, 2.0, std::nan(""))));     // no normal
  EXPECT_TRUE(std::isnan(cal.reflectivity(5000.0, 2.0, 1.0)));             // saturated
  EXPECT_TRUE(std::isnan(cal.reflectivity(-1.0, 2.0, 1.0)));
  EXPECT_TRUE(std::isnan(cal.reflectivity(std::nan(""), 2.0, 1.0)));
  EXPECT_TRUE(std::isnan(cal.response(std::nan(""), 1.0)));
  const IntensityCalibration dim(linearSpline(0.0, 1.0, 4, [](double) { return std::log(0.5); }),
                                 linearSpline(0.0, 45.0, 4, [](double) { return 0.0; }), 100.0, 1.0);
  EXPECT_TRUE(std::isnan(dim.reflectivity(0.2, 1.5, 1.0)));  // g = 0.5 < min_response
  const IntensityCalibration empty;
  EXPECT_TRUE(empty.empty());
  EXPECT_TRUE(std::isnan(empty.reflectivity(1.0, 1.0, 1.0)));
}

TEST(IntensityCalibration, ScaledAndAnchoredChangeOnlyTheScale) {
  const IntensityCalibration cal = inverseSquare();
  const IntensityCalibration twice = cal.scaled(2.0);
  EXPECT_NEAR(twice.response(3.0, 0.8), 2.0 * cal.response(3.0, 0.8), 1e-9);
  EXPECT_NEAR(twice.minResponse(), 2.0, 1e-12);
  EXPECT_THROW(cal.scaled(0.0), std::invalid_argument);
  // A target of ρ = 0.8 read by a scanner whose g is 3 × what cal says.
  std::vector<ReflectivityObservation> target;
  for (double r = 1.0; r < 8.0; r += 0.5) {
    target.push_back({0.8f, float(r), 0.9f, float(3.0 * 0.8 * cal.response(r, 0.9))});
  }
  target.push_back({0.8f, 1.0f, 0.9f, 4999.0f});  // one reading off: the median ignores it
  const IntensityCalibration anchored = cal.anchoredTo(target);
  EXPECT_NEAR(anchored.response(5.0, 1.0) / cal.response(5.0, 1.0), 3.0, 1e-5);
  EXPECT_THROW(cal.anchoredTo({{0.8f, 50.0f, 1.0f, 10.0f}}), std::invalid_argument);
}

TEST(IntensityCalibration, TextRoundTripsExactly) {
  const IntensityCalibration cal = inverseSquare().scaled(1.0 / 3.0);
  const std::string text = cal.toText();
  EXPECT_EQ(text.rfind("rmap_intensity_calibration 1\n", 0), 0u) << text;
  const IntensityCalibration back = IntensityCalibration::fromText(text);
  EXPECT_EQ(back.toText(), text);
  EXPECT_EQ(back.response(3.3, 0.7), cal.response(3.3, 0.7));
  EXPECT_EQ(back.saturation(), 5000.0);
  const IntensityCalibration unsaturated(cal.logRange(), cal.logIncidence(), std::numeric_limits<double>::infinity(), 0.0);
  EXPECT_NE(unsaturated.toText().find("saturation none\n"), std::string::npos);
  EXPECT_TRUE(std::isinf(IntensityCalibration::fromText(unsaturated.toText()).saturation()));
}

TEST(IntensityCalibration, FromTextAcceptsCommentsAndAnyKeyOrder) {
  const IntensityCalibration cal = IntensityCalibration::fromText(
      "# written by hand\n\nrmap_intensity_calibration 1   # version\n"
      "log_incidence 4 0 0 0 0\nlog_range 4 1 1 1 1\n"
      "saturation 255\nmin_response 0\nmax_incidence_deg 60\n\trange_m 0.2 10\n");
  EXPECT_NEAR(cal.response(1.0, 1.0), std::exp(1.0), 1e-12);
  EXPECT_EQ(cal.maxIncidence_deg(), 60.0);
  EXPECT_TRUE(std::isnan(cal.reflectivity(255.0, 1.0, 1.0)));
}

TEST(IntensityCalibration, FromTextNamesTheWrongLine) {
  const std::string good = inverseSquare().toText();
  expectFromTextError("", "expected 'rmap_intensity_calibration 1'");
  expectFromTextError("hello 1\n", "line 1: expected");
  expectFromTextError("\nrmap_intensity_calibration 2\n", "line 2: unsupported version '2'");
  expectFromTextError(good + "range_m 1 2\n", "line 9: duplicate range_m");
  expectFromTextError(good + "colour red\n", "line 9: unknown key 'colour'");
  std::string bad = good;
  bad.replace(bad.find("range_m"), 7, "range_m x");
  expectFromTextError(bad, "line 3: range_m: expected 2 value(s), got 3");
  bad = good;
  bad.replace(bad.find("log_range 8"), 11, "log_range 9");
  expectFromTextError(bad, "line 7: log_range: expected 10 value(s), got 9");
  bad = good;
  bad.replace(bad.find("max_incidence_deg 70"), 20, "max_incidence_deg 95");
  expectFromTextError(bad, "line 4: max_incidence_deg: must be in (0, 90)");
  bad = good;
  bad.replace(bad.find("min_response 1"), 14, "min_response nan");
  expectFromTextError(bad, "line 6: min_response: 'nan' is not a finite number");
  expectFromTextError("rmap_intensity_calibration 1\nrange_m 1 2\n", "missing max_incidence_deg");
}

}  // namespace
}  // namespace rmap::slam2d
