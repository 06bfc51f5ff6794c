#include "slam2d/intensity_calibration.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string_view>
#include <utility>

namespace rmap::slam2d {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::string_view kMagic = "rmap_intensity_calibration";
constexpr int kVersion = 1;

double incidenceDeg(double cos_incidence) {
  return std::acos(std::clamp(cos_incidence, 0.0, 1.0)) * (180.0 / std::numbers::pi);
}

void validateSpline(const CubicBSpline& s, const char* name) {
  auto fail = [&](const std::string& what) {
    throw std::invalid_argument(std::string("IntensityCalibration: ") + name + ": " + what);
  };
  if (s.coefficients.size() < 4) fail("needs at least 4 coefficients, got " + std::to_string(s.coefficients.size()));
  if (!std::isfinite(s.lo) || !std::isfinite(s.hi) || !(s.lo < s.hi)) fail("interval must be finite with lo < hi");
  for (double c : s.coefficients) {
    if (!std::isfinite(c)) fail("coefficients must be finite");
  }
}

std::string number(double v) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, end);
}

/// Whitespace-separated fields of one line, comment stripped.
std::vector<std::string_view> fields(std::string_view line) {
  if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    size_t j = i;
    while (j < line.size() && !std::isspace(static_cast<unsigned char>(line[j]))) ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

}  // namespace

int CubicBSpline::basis(double x, std::array<double, 4>& w) const {
  const int segments = static_cast<int>(coefficients.size()) - 3;
  const double u = (std::clamp(x, lo, hi) - lo) / (hi - lo) * segments;
  const int s = std::clamp(static_cast<int>(std::floor(u)), 0, segments - 1);
  const double t = u - s, t2 = t * t, t3 = t2 * t, m = 1.0 - t;
  w = {m * m * m / 6.0, (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0, (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0, t3 / 6.0};
  return s;
}

double CubicBSpline::operator()(double x) const {
  std::array<double, 4> w;
  const int s = basis(x, w);
  return w[0] * coefficients[s] + w[1] * coefficients[s + 1] + w[2] * coefficients[s + 2] + w[3] * coefficients[s + 3];
}

IntensityCalibration::IntensityCalibration(CubicBSpline log_range, CubicBSpline log_incidence, double saturation,
                                           double min_response)
    : log_range_(std::move(log_range)),
      log_incidence_(std::move(log_incidence)),
      saturation_(saturation),
      min_response_(min_response) {
  validateSpline(log_range_, "log_range");
  validateSpline(log_incidence_, "log_incidence");
  if (log_incidence_.lo != 0.0 || !(log_incidence_.hi < 90.0)) {
    throw std::invalid_argument("IntensityCalibration: log_incidence must span [0, max] degrees with max < 90");
  }
  if (!(saturation_ > 0.0)) throw std::invalid_argument("IntensityCalibration: saturation must be > 0");
  if (!(min_response_ >= 0.0) || !std::isfinite(min_response_)) {
    throw std::invalid_argument("IntensityCalibration: min_response must be finite and ≥ 0");
  }
}

double IntensityCalibration::minRange_m() const { return empty() ? kNaN : std::exp(log_range_.lo); }
double IntensityCalibration::maxRange_m() const { return empty() ? kNaN : std::exp(log_range_.hi); }

double IntensityCalibration::response(double range_m, double cos_incidence) const {
  if (empty() || !(range_m > 0.0) || !std::isfinite(range_m) || !(cos_incidence <= 1.0 + 1e-6)) return kNaN;
  const double log_r = std::log(range_m);
  const double alpha_deg = incidenceDeg(cos_incidence);
  if (log_r < log_range_.lo || log_r > log_range_.hi || !(alpha_deg <= log_incidence_.hi)) return kNaN;
  return std::exp(log_range_(log_r) + log_incidence_(alpha_deg));
}

double IntensityCalibration::reflectivity(double intensity, double range_m, double cos_incidence) const {
  if (!(intensity >= 0.0) || !(intensity < saturation_)) return kNaN;
  const double g = response(range_m, cos_incidence);
  if (!(g >= min_response_) || !(g > 0.0)) return kNaN;
  return intensity / g;
}

IntensityCalibration IntensityCalibration::scaled(double factor) const {
  if (!(factor > 0.0) || !std::isfinite(factor)) {
    throw std::invalid_argument("IntensityCalibration::scaled: factor must be finite and > 0");
  }
  IntensityCalibration out = *this;
  for (double& c : out.log_range_.coefficients) c += std::log(factor);  // B-spline weights sum to 1
  out.min_response_ *= factor;
  return out;
}

IntensityCalibration IntensityCalibration::anchoredTo(const std::vector<ReflectivityObservation>& reference) const {
  std::vector<double> ratios;
  for (const ReflectivityObservation& o : reference) {
    const double rho = reflectivity(o.intensity, o.range_m, o.cos_incidence);
    if (std::isfinite(rho) && rho > 0.0 && o.reflectivity > 0.0f) ratios.push_back(rho / o.reflectivity);
  }
  if (ratios.empty()) {
    throw std::invalid_argument("IntensityCalibration::anchoredTo: no reference reading inside the support");
  }
  auto mid = ratios.begin() + ratios.size() / 2;
  std::nth_element(ratios.begin(), mid, ratios.end());
  return scaled(*mid);
}

std::string IntensityCalibration::toText() const {
  if (empty()) throw std::invalid_argument("IntensityCalibration::toText: empty calibration");
  std::string out;
  out += std::string(kMagic) + " " + std::to_string(kVersion) + "\n";
  out += "# g(r, a) = exp(R(ln r) + A(a)); rho = I / g (see slam2d/intensity_calibration.h)\n";
  out += "range_m " + number(std::exp(log_range_.lo)) + " " + number(std::exp(log_range_.hi)) + "\n";
  out += "max_incidence_deg " + number(log_incidence_.hi) + "\n";
  out += "saturation " + (std::isfinite(saturation_) ? number(saturation_) : std::string("none")) + "\n";
  out += "min_response " + number(min_response_) + "\n";
  auto spline = [&](const char* key, const CubicBSpline& s) {
    out += key;
    out += ' ';
    out += std::to_string(s.coefficients.size());
    for (double c : s.coefficients) {
      out += ' ';
      out += number(c);
    }
    out += '\n';
  };
  spline("log_range", log_range_);
  spline("log_incidence", log_incidence_);
  return out;
}

IntensityCalibration IntensityCalibration::fromText(const std::string& text) {
  int line_no = 0;
  auto fail = [&](const std::string& what) {
    throw std::invalid_argument("intensity calibration line " + std::to_string(line_no) + ": " + what);
  };
  auto parse = [&](std::string_view field, const std::string& key) {
    double v = 0.0;
    const auto [end, ec] = std::from_chars(field.data(), field.data() + field.size(), v);
    if (ec != std::errc() || end != field.data() + field.size() || !std::isfinite(v)) {
      fail(key + ": '" + std::string(field) + "' is not a finite number");
    }
    return v;
  };

  bool have_version = false;
  std::map<std::string, std::vector<double>> values;
  double saturation = std::numeric_limits<double>::infinity();
  size_t pos = 0;
  while (pos <= text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    std::string_view line(text.data() + pos, end - pos);
    pos = end + 1;
    ++line_no;
    const std::vector<std::string_view> f = fields(line);
    if (f.empty()) continue;
    if (!have_version) {
      if (f[0] != kMagic) fail("expected '" + std::string(kMagic) + " " + std::to_string(kVersion) + "'");
      if (f.size() != 2 || f[1] != std::to_string(kVersion)) {
        fail("unsupported version '" + (f.size() > 1 ? std::string(f[1]) : std::string()) + "', this reader takes " +
             std::to_string(kVersion));
      }
      have_version = true;
      continue;
    }
    const std::string key(f[0]);
    if (values.count(key)) fail("duplicate " + key);
    std::vector<double> v;
    auto expect = [&](size_t n) {
      if (f.size() != n + 1) fail(key + ": expected " + std::to_string(n) + " value(s), got " + std::to_string(f.size() - 1));
    };
    if (key == "range_m") {
      expect(2);
      v = {parse(f[1], key), parse(f[2], key)};
      if (!(v[0] > 0.0 && v[0] < v[1])) fail("range_m: need 0 < min < max");
    } else if (key == "max_incidence_deg") {
      expect(1);
      v = {parse(f[1], key)};
      if (!(v[0] > 0.0 && v[0] < 90.0)) fail("max_incidence_deg: must be in (0, 90)");
    } else if (key == "saturation") {
      expect(1);
      if (f[1] != "none") {
        saturation = parse(f[1], key);
        if (!(saturation > 0.0)) fail("saturation: must be > 0 or 'none'");
      }
    } else if (key == "min_response") {
      expect(1);
      v = {parse(f[1], key)};
      if (!(v[0] >= 0.0)) fail("min_response: must be ≥ 0");
    } else if (key == "log_range" || key == "log_incidence") {
      if (f.size() < 2) fail(key + ": expected a coefficient count");
      const double n = parse(f[1], key);
      if (n != std::floor(n) || n < 4 || n > 100000) fail(key + ": coefficient count must be an integer ≥ 4");
      expect(static_cast<size_t>(n) + 1);
      for (size_t i = 2; i < f.size(); ++i) v.push_back(parse(f[i], key));
    } else {
      fail("unknown key '" + key + "'");
    }
    values[key] = std::move(v);
  }
  if (!have_version) fail("empty text, expected '" + std::string(kMagic) + " " + std::to_string(kVersion) + "'");
  for (const char* key : {"range_m", "max_incidence_deg", "saturation", "min_response", "log_range", "log_incidence"}) {
    if (!values.count(key)) {
      throw std::invalid_argument(std::string("intensity calibration: missing ") + key);
    }
  }
  const std::vector<double>& range = values["range_m"];
  CubicBSpline log_range{std::log(range[0]), std::log(range[1]), values["log_range"]};
  CubicBSpline log_incidence{0.0, values["max_incidence_deg"][0], values["log_incidence"]};
  return IntensityCalibration(std::move(log_range), std::move(log_incidence), saturation, values["min_response"][0]);
}

}  // namespace rmap::slam2d
