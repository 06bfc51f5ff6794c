#include "cli/replay_source.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>

#include "temp_files.h"

namespace rmap::cli {
namespace {

namespace fs = std::filesystem;

using ReplaySourceTest = TempFilesTest;

/// A FLASER line of `n` beams at `range` with one error reading (0) first.
std::string flaser(int n, double range, double x, double stamp) {
  std::ostringstream line;
  line << "FLASER " << n << " 0";
  for (int i = 1; i < n; ++i) line << ' ' << range;
  line << ' ' << x << " 0 0 " << x << " 0 0 " << std::fixed << stamp << " host " << stamp << '\n';
  return line.str();
}

TEST_F(ReplaySourceTest, CarmenScansCarryOdometryAndNoErrorReadings) {
  const std::string log = write("run.log", "ODOM 0 0 0 0 0 0 1.0 host 1.0\n" + flaser(181, 2.5, 0.0, 1.0) +
                                               "ODOM 0.5 0 0 0 0 0 1.5 host 1.5\n" + flaser(181, 2.0, 0.5, 2.0));
  const ReplaySource source = openReplaySource(ReplayFormat::kCarmen, {log}, {});
  ASSERT_EQ(source.frames, 2u);
  ASSERT_EQ(source.sensors.size(), 1u);
  EXPECT_EQ(source.sensors[0].kind(), rmap::v1::SensorDescription::LASER_2D);
  const ReplayFrame f = source.frame(1);
  ASSERT_TRUE(f.message.has_scan());
  const rmap::v1::LaserScan2D& scan = f.message.scan();
  EXPECT_EQ(f.stamp_ns, 2'000'000'000);
  EXPECT_EQ(scan.ranges_m_size(), 181);
  EXPECT_TRUE(std::isinf(scan.ranges_m(0)));  // the error reading
  EXPECT_FLOAT_EQ(scan.ranges_m(1), 2.0f);
  EXPECT_EQ(f.points, 180u);
  // 181 beams over 180° from the right, in whichever form reproduces the reader's angles.
  for (int i = 0; i < 181; i += 45) {
    const float a = scan.angles_rad().empty() ? scan.angle_min_rad() + static_cast<float>(i) * scan.angle_increment_rad()
                                              : scan.angles_rad(i);
    EXPECT_NEAR(a, -M_PI / 2 + i * M_PI / 180, 1e-6) << i;
  }
  ASSERT_TRUE(scan.has_odometry());
  EXPECT_NEAR(scan.odometry().x_m(), 0.5, 1e-9);
}

TEST_F(ReplaySourceTest, CarmenBadLineNamesFileAndLine) {
  const std::string log = write("bad.log", flaser(181, 2.5, 0.0, 1.0) + "FLASER 3 1 2\n");
  try {
    openReplaySource(ReplayFormat::kCarmen, {log}, {});
    ADD_FAILURE() << "accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.log:2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(openReplaySource(ReplayFormat::kCarmen, {log, log}, {}), std::runtime_error);
}

TEST_F(ReplaySourceTest, XyzScansAreMapFrameClouds) {
  const std::string file = write("s.dat", "NODE 1 2 0 0 0 0\n1 0 0\n0 1 0\nNODE 0 0 0 0 0 0\nNODE 5 0 0 0 0 0\n1 1 1\n");
  const ReplaySource source = openReplaySource(ReplayFormat::kXyzText, {file}, {});
  ASSERT_EQ(source.frames, 2u);  // the empty scan is skipped
  const ReplayFrame f = source.frame(0);
  ASSERT_TRUE(f.message.has_cloud());
  EXPECT_EQ(f.message.cloud().frame(), rmap::v1::PointCloud::MAP);
  EXPECT_EQ(f.points, 2u);
  EXPECT_DOUBLE_EQ(f.message.cloud().sensor_pose().position_m().x(), 1.0);
  EXPECT_FLOAT_EQ(f.message.cloud().xyz_m(0), 2.0f);  // 1 0 0 seen from (1, 2, 0)
  EXPECT_EQ(source.frame(1).stamp_ns, 100'000'000);
}

TEST_F(ReplaySourceTest, PcdFramesWithPosesAndNanPointsDropped) {
  const std::string head = "FIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nWIDTH 2\nHEIGHT 1\nDATA ascii\n";
  write("pcd/0.pcd", head + "1 0 0 5\nnan nan nan 0\n");
  write("pcd/1.pcd", head + "2 0 0 6\n3 0 0 7\n");
  ReplaySourceOptions options;
  options.poses_path = write("poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 10 0 1 0 0 0 0 1 0\n");
  const ReplaySource source = openReplaySource(ReplayFormat::kPcd, {(dir_ / "pcd").string()}, options);
  ASSERT_EQ(source.frames, 2u);
  EXPECT_TRUE(source.reads_per_frame);
  const ReplayFrame f0 = source.frame(0);
  EXPECT_EQ(f0.points, 1u);
  EXPECT_EQ(f0.dropped_points, 1u);
  EXPECT_EQ(f0.message.cloud().intensities_size(), 1);
  const ReplayFrame f1 = source.frame(1);
  EXPECT_EQ(f1.message.cloud().frame(), rmap::v1::PointCloud::SENSOR);
  EXPECT_DOUBLE_EQ(f1.message.cloud().sensor_pose().position_m().x(), 10.0);
  EXPECT_FLOAT_EQ(f1.message.cloud().intensities(1), 7.0f);
}

TEST_F(ReplaySourceTest, PoseCountMustMatchAndBadFramesAreNamed) {
  write("k/0.bin", std::string(16, '\0'));
  write("k/1.bin", std::string(17, '\0'));
  ReplaySourceOptions options;
  options.poses_path = write("one.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_THROW(openReplaySource(ReplayFormat::kVelodyneBin, {(dir_ / "k").string()}, options), std::runtime_error);
  const ReplaySource source = openReplaySource(ReplayFormat::kVelodyneBin, {(dir_ / "k").string()}, {});
  EXPECT_EQ(source.frame(0).points, 1u);
  try {
    source.frame(1);
    ADD_FAILURE() << "accepted a 17-byte frame";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("1.bin: 17 bytes"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rmap::cli
