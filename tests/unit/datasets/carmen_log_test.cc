#include "datasets/carmen_log.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

#include "datasets/slam_relations.h"

#include "dataset_test_support.h"

namespace rmap::datasets {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

/// A FLASER line with n beams of range r (the first one `first`), laser and robot poses.
std::string flaser(int n, const std::string& first, double r, const std::string& poses, const std::string& stamp) {
  std::ostringstream s;
  s << "FLASER " << n << " " << first;
  for (int i = 1; i < n; ++i) s << " " << r;
  s << " " << poses << " " << stamp << " host 0.5\n";
  return s.str();
}

void expectCarmenError(const std::string& text, const std::string& part) {
  expectParseError([](const std::string& c) { parseCarmenLog(c, "t.log"); }, text, part);
}

TEST(CarmenLog, FlaserFieldsPosesAndStamp) {
  const std::string text = "# comment\nPARAM robot_frontlaser_offset -0.04 nohost 0\n\n" +
                           flaser(181, "81.91", 2.0, "1.96 0 0 2 0 0", "976052857.337284") + "NEFF 12\n";
  const CarmenLog log = parseCarmenLog(text, "t.log");
  ASSERT_EQ(log.scans.size(), 1u);
  const CarmenScan& s = log.scans[0];
  EXPECT_EQ(s.line, 4u);
  EXPECT_EQ(s.scan.model, "FLASER");
  EXPECT_EQ(s.scan.stamp_ns, 976052857337284000);
  ASSERT_EQ(s.scan.ranges_m.size(), 181u);
  EXPECT_EQ(s.scan.ranges_m[0], std::numeric_limits<float>::infinity());
  EXPECT_EQ(s.scan.ranges_m[180], 2.0f);
  EXPECT_NEAR(s.laser_pose.x_m, 1.96, 1e-12);
  EXPECT_NEAR(s.robot_pose.x_m, 2.0, 1e-12);
  // the laser sits 4 cm behind the robot centre
  EXPECT_NEAR(s.scan.sensor_mount.x_m, -0.04, 1e-12);
  EXPECT_NEAR(s.scan.sensor_mount.y_m, 0.0, 1e-12);
  EXPECT_EQ(log.skipped.at("#"), 1u);
  EXPECT_EQ(log.skipped.at("PARAM"), 1u);
  EXPECT_EQ(log.skipped.at("NEFF"), 1u);
}

TEST(CarmenLog, FlaserAnglesFollowCarmensGuess) {
  for (const auto& [n, increment_deg] : {std::pair{181, 1.0}, {180, 1.0}, {361, 0.5}, {360, 0.5}}) {
    const CarmenLog log = parseCarmenLog(flaser(n, "1", 1.0, "0 0 0 0 0 0", "1.0"), "t.log");
    const std::vector<float>& a = log.scans.at(0).scan.angles_rad;
    ASSERT_EQ(a.size(), size_t(n));
    EXPECT_NEAR(a.front(), -90 * kDeg, 1e-6) << n;
    EXPECT_NEAR(a[1] - a[0], increment_deg * kDeg, 1e-6) << n;
    // odd counts end at +90°, even counts one step short of it
    EXPECT_NEAR(a.back(), (n % 2 ? 90.0 : 90.0 - increment_deg) * kDeg, 1e-6) << n;
  }
}

TEST(CarmenLog, NoReturnsAndErrorReadings) {
  // 81.83 is the largest reading: it and anything within 1 % below are no returns
  const std::string text = flaser(4, "81.83", 5.0, "0 0 0 0 0 0", "1") + flaser(4, "0", 81.2, "0 0 0 0 0 0", "2") +
                           flaser(4, "80.9", 3.0, "0 0 0 0 0 0", "3");
  const CarmenLog log = parseCarmenLog(text, "t.log");
  EXPECT_NEAR(log.flaser_no_return_m, 0.99 * 81.83, 1e-4);
  EXPECT_EQ(log.scans[0].scan.ranges_m[0], std::numeric_limits<float>::infinity());
  EXPECT_EQ(log.scans[0].scan.ranges_m[1], 5.0f);
  EXPECT_TRUE(std::isnan(log.scans[1].scan.ranges_m[0]));  // 0 = error reading
  EXPECT_EQ(log.scans[1].scan.ranges_m[1], std::numeric_limits<float>::infinity());
  EXPECT_EQ(log.scans[2].scan.ranges_m[0], 80.9f);  // a real long return
  EXPECT_EQ(log.scans[2].scan.range_max_m, log.flaser_no_return_m);
  // a given no-return range replaces the derived one
  CarmenReadOptions options;
  options.flaser_no_return_m = 4.0f;
  const CarmenLog fixed = parseCarmenLog(text, "t.log", options);
  EXPECT_EQ(fixed.flaser_no_return_m, 4.0f);
  EXPECT_EQ(fixed.scans[0].scan.ranges_m[1], std::numeric_limits<float>::infinity());
  EXPECT_EQ(fixed.scans[2].scan.ranges_m[1], 3.0f);
}

TEST(CarmenLog, RobotLaserWithAndWithoutRemissions) {
  const std::string tail = " 1 2 0.5 1.1 2 0.5 0.3 0.1 0 0 0 1134864642.914187 b21 0.43\n";
  const std::string plain = "ROBOTLASER1 0 -1.570796 3.150447 0.5 80 0.01 0 3 1.5 81.91 2.0 0" + tail;
  const std::string with = "ROBOTLASER1 5 -1.0 2.0 1.0 30 0.01 1 3 1.5 40 2.0 3 100 0 250" + tail;
  const CarmenLog log = parseCarmenLog(plain + with, "t.log");
  ASSERT_EQ(log.scans.size(), 2u);
  const slam2d::LaserScan& a = log.scans[0].scan;
  EXPECT_EQ(a.model, "ROBOTLASER1/0");
  EXPECT_EQ(a.range_max_m, 80.0f);
  EXPECT_EQ(a.ranges_m[1], std::numeric_limits<float>::infinity());  // 81.91 ≥ max range
  EXPECT_TRUE(a.intensities.empty());
  EXPECT_NEAR(a.angles_rad[2], -1.570796 + 1.0, 1e-6);
  EXPECT_EQ(a.stamp_ns, 1134864642914187000);
  EXPECT_NEAR(log.scans[0].laser_pose.theta_rad, 0.5, 1e-12);
  // laser 10 cm behind the robot along world x, robot heading 0.5 rad
  EXPECT_NEAR(a.sensor_mount.x_m, -0.1 * std::cos(0.5), 1e-12);
  EXPECT_NEAR(a.sensor_mount.y_m, 0.1 * std::sin(0.5), 1e-12);
  EXPECT_NEAR(a.sensor_mount.theta_rad, 0.0, 1e-12);
  const slam2d::LaserScan& b = log.scans[1].scan;
  EXPECT_EQ(b.model, "ROBOTLASER1/5");
  ASSERT_EQ(b.intensities.size(), 3u);
  EXPECT_EQ(b.intensities[2], 250.0f);
  EXPECT_EQ(b.ranges_m[1], std::numeric_limits<float>::infinity());  // 40 ≥ 30
  EXPECT_NEAR(b.angles_rad[1], 0.0, 1e-6);
}

TEST(CarmenLog, OdometryOrderAndIncrementsOfACorrectedLog) {
  // Corrected-log layout: each scan's pose, then ODOM restarting from it.
  const std::string text = flaser(2, "1", 1, "1 1 0 1 1 0", "10.0") + "ODOM 1 1 0 0 0 0 10.1 h 0\n" +
                           "ODOM 1.5 1 0.1 0.5 0 0 10.2 h 0\n" + flaser(2, "1", 1, "1.6 1.1 0.12 1.6 1.1 0.12", "10.3") +
                           "ODOM 1.6 1.1 0.12 0 0 0 10.4 h 0\n" + flaser(2, "1", 1, "1.6 1.1 0.12 1.6 1.1 0.12", "10.5");
  const CarmenLog log = parseCarmenLog(text, "t.log");
  ASSERT_EQ(log.odometry.size(), 3u);
  EXPECT_EQ(log.odometry[1].stamp_ns, 10200000000);
  EXPECT_EQ(log.odometry[1].velocity_mps, 0.5);
  EXPECT_EQ(log.scans[0].odometry_before, 0u);
  EXPECT_EQ(log.scans[1].odometry_before, 2u);
  EXPECT_EQ(log.scans[2].odometry_before, 3u);
  EXPECT_TRUE(odometryRestartsAtScans(log));
  const std::vector<std::optional<slam2d::Pose2>> odo = odometryFromOdomIncrements(log);
  ASSERT_EQ(odo.size(), 3u);
  ASSERT_TRUE(odo[0] && odo[1]);
  EXPECT_EQ(odo[0]->x_m, 0.0);
  // wheel motion from the first pose (1,1,0) to the last ODOM (1.5,1,0.1); the correction to 1.6 is not seen
  EXPECT_NEAR(odo[1]->x_m, 0.5, 1e-12);
  EXPECT_NEAR(odo[1]->y_m, 0.0, 1e-12);
  EXPECT_NEAR(odo[1]->theta_rad, 0.1, 1e-12);
  // only the restart at scan 2's pose follows it: the motion to scan 3 is unknown, not zero
  EXPECT_FALSE(odo[2].has_value());
}

TEST(CarmenLog, RawOdometryDoesNotRestart) {
  const std::string text = flaser(2, "1", 1, "0 0 0 0 0 0", "1") + "ODOM 0.1 0 0 0 0 0 1.1 h 0\n" +
                           flaser(2, "1", 1, "0.2 0 0 0.2 0 0", "1.2") + "ODOM 0.3 0 0 0 0 0 1.3 h 0\n";
  EXPECT_FALSE(odometryRestartsAtScans(parseCarmenLog(text, "t.log")));
}

TEST(CarmenLog, MalformedLinesNameTheLine) {
  const std::string good = flaser(3, "1", 1, "0 0 0 0 0 0", "1");
  expectCarmenError(good + "FLASER 3 1 2 3 0 0 0 0 0 0 1 host\n", "t.log:2: FLASER needs 14 fields");
  expectCarmenError(good + "FLASER 1 1 0 0 0 0 0 0 1 h 0\n", "t.log:2: FLASER beam count");
  expectCarmenError("FLASER x\n", "t.log:1: malformed number \"x\"");
  expectCarmenError(good + good + "ODOM 0 0 nan 0 0 0 1 h 0\n", "t.log:3: non-finite value");
  expectCarmenError("ODOM 0 0 0 0 0 0 1 h\n", "t.log:1: ODOM needs 10 fields");
  expectCarmenError("ODOM 0 0 0 0 0 0 1.5x3 h 0\n", "t.log:1: malformed number");
  expectCarmenError("ROBOTLASER1 0 -1.5 3.1 0.5 80 0.01 0 2 1 1 1 5 0 0 0 0 0 0 0 0 0 0 0 1 h 0\n",
              "t.log:1: ROBOTLASER1 has 1 remissions for 2 beams");
  expectCarmenError("ROBOTLASER1 0 -1.5 3.1 0.5 80 0.01 0 2 1 1 0 0 0 0 0 0 0 0 0 0 0 1 h 0\n",
              "t.log:1: ROBOTLASER1 needs 26 fields");
}

TEST(CarmenLog, StampsAreExact) {
  EXPECT_EQ(parseCarmenStampNs("976052857.337284", "t", 1), 976052857337284000);
  EXPECT_EQ(parseCarmenStampNs("218.817", "t", 1), 218817000000);
  EXPECT_EQ(parseCarmenStampNs("12", "t", 1), 12000000000);
  EXPECT_EQ(parseCarmenStampNs("0.0000000019", "t", 1), 1);
  EXPECT_EQ(parseCarmenStampNs("-0.042", "t", 1), -42000000);
  EXPECT_EQ(parseCarmenStampNs("1.13486e+09", "t", 1), 1134860000000000000);
  EXPECT_THROW(parseCarmenStampNs("", "t", 1), std::runtime_error);
  EXPECT_THROW(parseCarmenStampNs("1e12", "t", 1), std::runtime_error);
  EXPECT_THROW(parseCarmenStampNs("nan", "t", 1), std::runtime_error);
}

// Found by tests/fuzz/carmen_log_fuzz.cc: ten plain digits overflowed int64 nanoseconds (UB).
TEST(CarmenLog, PlainStampsBeyondTheRangeAreRefused) {
  EXPECT_EQ(parseCarmenStampNs("8999999999.999999999", "t", 1), 8999999999999999999);
  EXPECT_THROW(parseCarmenStampNs("9710505559.981874", "t", 1), std::runtime_error);
  EXPECT_THROW(parseCarmenStampNs("9999999999", "t", 1), std::runtime_error);
}

const std::string kData = RMAP_SHARED_DATA_DIR;

TEST(CarmenLog, RealCorrectedAndRawLogs) {
  const std::string corrected = kData + "/carmen-2d/intel-corrected.log.gz";
  const std::string robotlaser = kData + "/carmen-2d/csail-corrected-subset.robotlaser1.log.gz";
  if (!std::filesystem::exists(corrected) || !std::filesystem::exists(robotlaser)) {
    GTEST_SKIP() << "shared CARMEN logs not found under " << kData;
  }
  const CarmenLog intel = readCarmenLog(corrected);
  EXPECT_EQ(intel.scans.size(), 910u);
  EXPECT_EQ(intel.odometry.size(), 14541u);
  EXPECT_EQ(intel.scans[0].scan.ranges_m.size(), 180u);
  EXPECT_NEAR(intel.flaser_no_return_m, 0.99 * 81.83, 1e-3);
  EXPECT_TRUE(odometryRestartsAtScans(intel));
  const CarmenLog csail = readCarmenLog(robotlaser);
  EXPECT_EQ(csail.scans.size(), 686u);
  EXPECT_EQ(csail.scans[0].scan.ranges_m.size(), 361u);
  EXPECT_NEAR(csail.scans[0].scan.angles_rad.back(), std::numbers::pi / 2, 2e-4);
}

TEST(CarmenLog, RawIntelCarriesEveryRelationStamp) {
  const std::string raw = kData + "/carmen-2d-raw/intel.clf.bz2";
  const std::string relations = kData + "/relations/intel.relations";
  if (!std::filesystem::exists(raw) || !std::filesystem::exists(relations)) {
    GTEST_SKIP() << "raw intel log or its relations not found under " << kData;
  }
  const CarmenLog log = readCarmenLog(raw);
  EXPECT_EQ(log.scans.size(), 13631u);
  EXPECT_EQ(log.odometry.size(), 26915u);
  EXPECT_FALSE(odometryRestartsAtScans(log));
  std::set<int64_t> stamps;
  for (const CarmenScan& s : log.scans) stamps.insert(s.scan.stamp_ns);
  const std::vector<SlamRelation> rel = readSlamRelations(relations);
  ASSERT_EQ(rel.size(), 2984u);
  for (const SlamRelation& r : rel) {
    ASSERT_TRUE(stamps.count(r.from_stamp_ns) && stamps.count(r.to_stamp_ns)) << "line " << r.line;
  }
}

}  // namespace
}  // namespace rmap::datasets
