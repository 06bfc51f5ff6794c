#include "datasets/carmen_log.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "datasets/compressed_file.h"
#include "datasets/text_fields.h"

namespace rmap::datasets {
namespace {

using slam2d::Pose2;

/// robot⁻¹ · laser, differences taken before rotating: exactly the identity when the log gives
/// the laser the robot's pose (as corrected logs do), where slam2d::between leaves ~1e-16 m of
/// rounding that differs from scan to scan and cannot be declared once for a robot.
Pose2 mountOf(const Pose2& robot, const Pose2& laser) {
  const double c = std::cos(robot.theta_rad), s = std::sin(robot.theta_rad);
  const double dx = laser.x_m - robot.x_m, dy = laser.y_m - robot.y_m;
  return {c * dx + s * dy, -s * dx + c * dy, slam2d::normalizeAngle(laser.theta_rad - robot.theta_rad)};
}

constexpr float kNoReturn = std::numeric_limits<float>::infinity();
constexpr float kErrorReading = std::numeric_limits<float>::quiet_NaN();

/// The fields of one line and where it came from, for parsing with errors that say where.
class Fields {
 public:
  Fields(const std::vector<std::string_view>& fields, const std::string& source, size_t line)
      : fields_(fields), source_(source), line_(line) {}

  size_t size() const { return fields_.size(); }

  double number(size_t i) const {
    const double v = parseNumber(fields_[i], source_, line_);
    if (!std::isfinite(v)) fail("non-finite value \"" + std::string(fields_[i]) + "\" in field " + std::to_string(i));
    return v;
  }

  /// A count field: a whole number in [min, max].
  size_t count(size_t i, size_t min, size_t max, const char* what) const {
    const double v = number(i);
    if (v != std::floor(v) || v < double(min) || v > double(max)) {
      fail(std::string(what) + " must be a whole number in [" + std::to_string(min) + ", " + std::to_string(max) +
           "], got \"" + std::string(fields_[i]) + "\"");
    }
    return static_cast<size_t>(v);
  }

  Pose2 pose(size_t i) const { return {number(i), number(i + 1), number(i + 2)}; }

  int64_t stamp(size_t i) const { return parseCarmenStampNs(fields_[i], source_, line_); }

  void expectSize(size_t expected, const std::string& layout) const {
    if (fields_.size() != expected) {
      fail(std::string(fields_[0]) + " needs " + std::to_string(expected) + " fields (" + layout + "), got " +
           std::to_string(fields_.size()));
    }
  }

  [[noreturn]] void fail(const std::string& problem) const { throwAt(source_, line_, problem); }

 private:
  const std::vector<std::string_view>& fields_;
  const std::string& source_;
  size_t line_;
};

// The beam count bounds the field count, so a corrupt count cannot make the reader allocate wildly.
constexpr size_t kMaxBeams = 100000;

void readRanges(const Fields& f, size_t first, size_t n, slam2d::LaserScan& scan) {
  scan.ranges_m.resize(n);
  for (size_t i = 0; i < n; ++i) scan.ranges_m[i] = static_cast<float>(f.number(first + i));
}

/// FLASER beam spacing: CARMEN's guess for a 180° scanner (see the header).
double flaserIncrementRad(size_t n) {
  return n % 2 == 1 ? std::numbers::pi / double(n - 1) : std::numbers::pi / double(n);
}

CarmenScan parseFlaser(const Fields& f, size_t odometry_before, size_t line) {
  if (f.size() < 2) f.fail("FLASER needs a beam count");
  const size_t n = f.count(1, 2, kMaxBeams, "FLASER beam count");
  f.expectSize(2 + n + 9, "FLASER n r_1..r_n x y theta odom_x odom_y odom_theta ipc_timestamp host logger_timestamp");
  CarmenScan s;
  s.line = line;
  s.odometry_before = odometry_before;
  s.scan.model = "FLASER";
  readRanges(f, 2, n, s.scan);
  s.scan.angles_rad.resize(n);
  const double increment = flaserIncrementRad(n);
  for (size_t i = 0; i < n; ++i) s.scan.angles_rad[i] = static_cast<float>(-std::numbers::pi / 2 + i * increment);
  s.laser_pose = f.pose(2 + n);
  s.robot_pose = f.pose(2 + n + 3);
  s.scan.stamp_ns = f.stamp(2 + n + 6);
  return s;
}

CarmenScan parseRobotLaser(const Fields& f, size_t odometry_before, size_t line) {
  if (f.size() < 10) f.fail("ROBOTLASER1 needs type start_angle fov resolution max_range accuracy remission_mode n");
  const size_t n = f.count(8, 2, kMaxBeams, "ROBOTLASER1 beam count");
  if (f.size() < 9 + n + 1) f.fail("ROBOTLASER1 ends before its remission count");
  const size_t m = f.count(9 + n, 0, kMaxBeams, "ROBOTLASER1 remission count");
  if (m != 0 && m != n) {
    f.fail("ROBOTLASER1 has " + std::to_string(m) + " remissions for " + std::to_string(n) + " beams (need 0 or n)");
  }
  f.expectSize(9 + n + 1 + m + 14,
               "ROBOTLASER1 type start_angle fov resolution max_range accuracy remission_mode n r_1..r_n m "
               "remissions laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv forward_safety "
               "side_safety turn_axis ipc_timestamp host logger_timestamp");
  CarmenScan s;
  s.line = line;
  s.odometry_before = odometry_before;
  s.scan.model = "ROBOTLASER1/" + std::to_string(f.count(1, 0, 1000, "ROBOTLASER1 laser type"));
  const double start = f.number(2), resolution = f.number(4), max_range = f.number(5);
  if (!(resolution > 0.0)) f.fail("ROBOTLASER1 angular resolution must be > 0");
  if (!(max_range > 0.0)) f.fail("ROBOTLASER1 max range must be > 0");
  readRanges(f, 9, n, s.scan);
  s.scan.angles_rad.resize(n);
  for (size_t i = 0; i < n; ++i) s.scan.angles_rad[i] = static_cast<float>(start + i * resolution);
  s.scan.intensities.resize(m);
  for (size_t i = 0; i < m; ++i) s.scan.intensities[i] = static_cast<float>(f.number(10 + n + i));
  s.scan.range_max_m = static_cast<float>(max_range);
  const size_t tail = 10 + n + m;
  s.laser_pose = f.pose(tail);
  s.robot_pose = f.pose(tail + 3);
  s.scan.stamp_ns = f.stamp(tail + 11);
  return s;
}

CarmenOdometry parseOdom(const Fields& f, size_t line) {
  f.expectSize(10, "ODOM x y theta tv rv accel ipc_timestamp host logger_timestamp");
  CarmenOdometry o;
  o.pose = f.pose(1);
  o.velocity_mps = f.number(4);
  o.turn_rate_radps = f.number(5);
  f.number(6);  // acceleration: unused, but a malformed one is still an error
  o.stamp_ns = f.stamp(7);
  o.line = line;
  return o;
}

/// Marks no returns and error readings; range_max_m is the no-return range.
void applyRangeConventions(slam2d::LaserScan& scan) {
  for (float& r : scan.ranges_m) {
    if (r >= scan.range_max_m) {
      r = kNoReturn;
    } else if (!(r > 0.0f)) {
      r = kErrorReading;
    }
  }
}

}  // namespace

int64_t parseCarmenStampNs(std::string_view field, const std::string& source, size_t line) {
  // Plain decimals ("976052857.337284") are taken digit by digit; anything
  // else (signs, exponents: "1.13486e+09", "-0.042" occur in the corrected
  // logs) goes through a double, which is exact enough for such stamps.
  const size_t dot = field.find('.');
  const std::string_view whole = field.substr(0, dot);
  const std::string_view fraction = dot == std::string_view::npos ? std::string_view{} : field.substr(dot + 1);
  const auto digits = [](std::string_view d) {
    return std::all_of(d.begin(), d.end(), [](char c) { return c >= '0' && c <= '9'; });
  };
  if (!whole.empty() && whole.size() <= 10 && digits(whole) && digits(fraction)) {
    int64_t ns = 0;
    for (char c : whole) ns = ns * 10 + (c - '0');
    // The range of the other forms; ten digits could reach 1e10 s, beyond int64 nanoseconds.
    if (ns >= 9'000'000'000) throwAt(source, line, "timestamp out of range \"" + std::string(field) + "\"");
    int64_t frac_ns = 0, scale = 100000000;
    for (char c : fraction.substr(0, 9)) {  // digits below 1 ns are dropped
      frac_ns += (c - '0') * scale;
      scale /= 10;
    }
    return ns * 1000000000 + frac_ns;
  }
  const double s = parseNumber(field, source, line);
  if (!(std::abs(s) < 9.0e9)) throwAt(source, line, "timestamp out of range \"" + std::string(field) + "\"");
  return std::llround(s * 1e9);
}

CarmenLog parseCarmenLog(std::string_view text, const std::string& source, const CarmenReadOptions& options) {
  CarmenLog log;
  TextLines lines(text);
  std::string_view line;
  std::vector<std::string_view> fields;
  while (lines.next(line)) {
    fields.resize(splitFields(line, nullptr, 0));
    if (fields.empty()) continue;
    splitFields(line, fields.data(), fields.size());
    const std::string_view name = fields[0];
    const Fields f(fields, source, lines.number());
    if (name == "FLASER") {
      log.scans.push_back(parseFlaser(f, log.odometry.size(), lines.number()));
    } else if (name == "ROBOTLASER1") {
      log.scans.push_back(parseRobotLaser(f, log.odometry.size(), lines.number()));
    } else if (name == "ODOM") {
      log.odometry.push_back(parseOdom(f, lines.number()));
    } else {
      ++log.skipped[name[0] == '#' ? std::string("#") : std::string(name)];
    }
  }
  float largest_flaser = 0.0f;
  for (const CarmenScan& s : log.scans) {
    if (s.scan.model != "FLASER") continue;
    for (float r : s.scan.ranges_m) largest_flaser = std::max(largest_flaser, r);
  }
  log.flaser_no_return_m = options.flaser_no_return_m > 0.0f ? options.flaser_no_return_m : 0.99f * largest_flaser;
  for (CarmenScan& s : log.scans) {
    if (s.scan.model == "FLASER") s.scan.range_max_m = log.flaser_no_return_m;
    s.scan.sensor_mount = mountOf(s.robot_pose, s.laser_pose);
    applyRangeConventions(s.scan);
  }
  return log;
}

CarmenLog readCarmenLog(const std::string& path, const CarmenReadOptions& options) {
  return parseCarmenLog(readFileMaybeCompressed(path), path, options);
}

bool odometryRestartsAtScans(const CarmenLog& log) {
  size_t followed = 0, restarted = 0;
  for (const CarmenScan& s : log.scans) {
    if (s.odometry_before >= log.odometry.size()) continue;
    ++followed;
    const Pose2 d = slam2d::between(s.robot_pose, log.odometry[s.odometry_before].pose);
    restarted += std::abs(d.x_m) <= 1e-6 && std::abs(d.y_m) <= 1e-6 && std::abs(d.theta_rad) <= 1e-6;
  }
  return followed > 0 && restarted >= 0.9 * double(followed);
}

std::vector<std::optional<Pose2>> odometryFromOdomIncrements(const CarmenLog& log) {
  std::vector<std::optional<Pose2>> odometry;
  odometry.reserve(log.scans.size());
  if (log.scans.empty()) return odometry;
  Pose2 accumulated;
  odometry.push_back(accumulated);
  for (size_t k = 0; k + 1 < log.scans.size(); ++k) {
    const CarmenScan& now = log.scans[k];
    const CarmenScan& next = log.scans[k + 1];
    // The first ODOM after a scan restarts at its pose; only later ones hold wheel motion.
    if (next.odometry_before < now.odometry_before + 2) {
      odometry.push_back(std::nullopt);
      continue;
    }
    accumulated = accumulated * slam2d::between(now.robot_pose, log.odometry[next.odometry_before - 1].pose);
    odometry.push_back(accumulated);
  }
  return odometry;
}

}  // namespace rmap::datasets
