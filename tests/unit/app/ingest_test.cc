#include "app/ingest.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace rmap::app {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

v1::Hello hello(const std::string& robot_id = "robot-1", const std::string& map = "lab", double resolution = 0.0) {
  v1::Hello h;
  h.set_robot_id(robot_id);
  h.set_map(map);
  h.set_resolution_m(resolution);
  return h;
}

v1::RobotMessage cloudMessage(std::initializer_list<float> xyz) {
  v1::RobotMessage m;
  m.set_seq(1);
  for (const float v : xyz) m.mutable_cloud()->add_xyz_m(v);
  return m;
}

v1::RobotMessage scanMessage(std::initializer_list<float> ranges) {
  v1::RobotMessage m;
  m.set_seq(1);
  v1::LaserScan2D& scan = *m.mutable_scan();
  scan.set_angle_min_rad(-1.0f);
  scan.set_angle_increment_rad(0.01f);
  scan.set_range_min_m(0.1f);
  scan.set_range_max_m(30.0f);
  for (const float r : ranges) scan.add_ranges_m(r);
  return m;
}

v1::RobotMessage imageMessage(v1::CameraImage::Encoding encoding, const std::string& data, uint32_t width = 0,
                              uint32_t height = 0) {
  v1::RobotMessage m;
  m.set_seq(1);
  v1::CameraImage& image = *m.mutable_image();
  image.set_encoding(encoding);
  image.set_data(data);
  image.set_width(width);
  image.set_height(height);
  return m;
}

void setOrientation(v1::Pose3& pose, double w, double x, double y, double z) {
  pose.mutable_orientation()->set_w(w);
  pose.mutable_orientation()->set_x(x);
  pose.mutable_orientation()->set_y(y);
  pose.mutable_orientation()->set_z(z);
}

std::string check(const v1::RobotMessage& message, const LimitsConfig& limits = {}) {
  return checkDataMessage(message, limits, map3d::Grid(0.1));
}

TEST(ValidName, AcceptsTheAllowedCharacters) {
  EXPECT_TRUE(validName("a"));
  EXPECT_TRUE(validName("Robot_1.left-arm"));
  EXPECT_TRUE(validName(std::string(64, 'x')));
}

TEST(ValidName, RejectsEmptyLongAndOtherCharacters) {
  EXPECT_FALSE(validName(""));
  EXPECT_FALSE(validName(std::string(65, 'x')));
  const std::string bad_names[] = {"a b", "a/b", "a:b", "caf\xC3\xA9", std::string("a\0b", 3), "a%20"};
  for (const std::string& bad : bad_names) {
    EXPECT_FALSE(validName(bad)) << bad;
  }
}

TEST(CheckHello, AcceptsAValidHello) {
  EXPECT_EQ(checkHello(hello()), "");
  EXPECT_EQ(checkHello(hello("r", "m", 0.05)), "");
}

TEST(CheckHello, RejectsBadIdsAndMapNames) {
  EXPECT_NE(checkHello(hello("")), "");
  EXPECT_NE(checkHello(hello("robot 1")), "");
  EXPECT_NE(checkHello(hello("robot-1", "")), "");
  EXPECT_NE(checkHello(hello("robot-1", "../lab")), "");
}

TEST(CheckHello, ResolutionBounds) {
  for (const double ok : {0.0, 0.005, 0.1, 10.0}) EXPECT_EQ(checkHello(hello("r", "m", ok)), "") << ok;
  for (const double bad : {0.0049, 10.01, -0.1, double(kNaN), double(kInf)}) {
    EXPECT_NE(checkHello(hello("r", "m", bad)), "") << bad;
  }
}

TEST(CheckHello, RejectsABadSensorMount) {
  v1::Hello h = hello();
  setOrientation(*h.add_sensors()->mutable_mount(), 0.5, 0.0, 0.0, 0.0);
  EXPECT_NE(checkHello(h), "");
}

TEST(CheckCloud, AcceptsAValidCloud) {
  v1::RobotMessage m = cloudMessage({1, 2, 3, 4, 5, 6});
  m.mutable_cloud()->add_intensities(0.5f);
  m.mutable_cloud()->add_intensities(0.7f);
  EXPECT_EQ(check(m), "");
}

TEST(CheckCloud, RejectsEmptyAndPartialPoints) {
  EXPECT_NE(check(cloudMessage({})), "");
  EXPECT_NE(check(cloudMessage({1, 2, 3, 4})), "");
}

TEST(CheckCloud, RejectsNonFinitePoints) {
  EXPECT_NE(check(cloudMessage({1, 2, 3, 4, kNaN, 6})), "");
  EXPECT_NE(check(cloudMessage({kInf, 2, 3})), "");
}

TEST(CheckCloud, RejectsIntensityCountMismatch) {
  v1::RobotMessage m = cloudMessage({1, 2, 3, 4, 5, 6});
  m.mutable_cloud()->add_intensities(0.5f);
  EXPECT_NE(check(m), "");
}

TEST(CheckCloud, RejectsMorePointsThanTheLimit) {
  LimitsConfig limits;
  limits.max_points_per_cloud = 2;
  EXPECT_EQ(check(cloudMessage({1, 2, 3, 4, 5, 6}), limits), "");
  EXPECT_NE(check(cloudMessage({1, 2, 3, 4, 5, 6, 7, 8, 9}), limits), "");
}

TEST(CheckCloud, RejectsANonUnitQuaternion) {
  v1::RobotMessage m = cloudMessage({1, 2, 3});
  setOrientation(*m.mutable_cloud()->mutable_sensor_pose(), 2.0, 0.0, 0.0, 0.0);
  EXPECT_NE(check(m), "");
}

TEST(CheckCloud, AcceptsUnitAndAllZeroQuaternions) {
  v1::RobotMessage m = cloudMessage({1, 2, 3});
  EXPECT_EQ(check(m), "");  // orientation unset: all zero
  setOrientation(*m.mutable_cloud()->mutable_sensor_pose(), std::sqrt(0.5), 0.0, 0.0, std::sqrt(0.5));
  EXPECT_EQ(check(m), "");
}

TEST(CheckCloud, RejectsANonFinitePosition) {
  v1::RobotMessage m = cloudMessage({1, 2, 3});
  m.mutable_cloud()->mutable_sensor_pose()->mutable_position_m()->set_y(std::nan(""));
  EXPECT_NE(check(m), "");
}

TEST(CheckScan, AcceptsAValidScanWithInfiniteRanges) {
  EXPECT_EQ(check(scanMessage({1.0f, kInf, 40.0f})), "");
}

TEST(CheckScan, RejectsNaNAndNegativeRanges) {
  EXPECT_NE(check(scanMessage({1.0f, kNaN})), "");
  EXPECT_NE(check(scanMessage({1.0f, -0.5f})), "");
  EXPECT_NE(check(scanMessage({-kInf})), "");
  EXPECT_NE(check(scanMessage({})), "");
}

TEST(CheckScan, RangeLimitsMustBeOrderedAndFinite) {
  const std::pair<float, float> bad[] = {{-0.1f, 30.0f}, {5.0f, 5.0f}, {5.0f, 1.0f}, {0.1f, kInf}, {kNaN, 30.0f}};
  for (const auto& [min, max] : bad) {
    v1::RobotMessage m = scanMessage({1.0f});
    m.mutable_scan()->set_range_min_m(min);
    m.mutable_scan()->set_range_max_m(max);
    EXPECT_NE(check(m), "") << min << " " << max;
  }
}

TEST(CheckScan, AnglesMustMatchTheRanges) {
  v1::RobotMessage m = scanMessage({1.0f, 2.0f});
  m.mutable_scan()->add_angles_rad(0.0f);
  EXPECT_NE(check(m), "");
  m.mutable_scan()->add_angles_rad(0.1f);
  EXPECT_EQ(check(m), "");
}

TEST(CheckScan, RejectsAZeroIncrementWithoutAngles) {
  v1::RobotMessage m = scanMessage({1.0f, 2.0f});
  m.mutable_scan()->set_angle_increment_rad(0.0f);
  EXPECT_NE(check(m), "");
  m.mutable_scan()->add_angles_rad(0.0f);
  m.mutable_scan()->add_angles_rad(0.1f);
  EXPECT_EQ(check(m), "");
}

TEST(CheckScan, RejectsIntensityMismatchAndBadOdometry) {
  v1::RobotMessage m = scanMessage({1.0f, 2.0f});
  m.mutable_scan()->add_intensities(1.0f);
  EXPECT_NE(check(m), "");
  v1::RobotMessage odometry = scanMessage({1.0f});
  odometry.mutable_scan()->mutable_odometry()->set_theta_rad(kInf);
  EXPECT_NE(check(odometry), "");
}

TEST(CheckImage, ChecksJpegMagic) {
  EXPECT_EQ(check(imageMessage(v1::CameraImage::JPEG, "\xFF\xD8\xFF\xE0rest")), "");
  EXPECT_NE(check(imageMessage(v1::CameraImage::JPEG, "\x89PNG\r\n\x1A\n")), "");
  EXPECT_NE(check(imageMessage(v1::CameraImage::JPEG, "\xFF\xD8")), "");
}

TEST(CheckImage, ChecksPngMagic) {
  EXPECT_EQ(check(imageMessage(v1::CameraImage::PNG, "\x89PNG\r\n\x1A\nIHDR")), "");
  EXPECT_NE(check(imageMessage(v1::CameraImage::PNG, "\x89PNG\r\n")), "");
  EXPECT_NE(check(imageMessage(v1::CameraImage::PNG, "\xFF\xD8\xFF\xE0rest")), "");
}

TEST(CheckImage, RawImagesNeedWidthTimesHeightTimesChannelsBytes) {
  EXPECT_EQ(check(imageMessage(v1::CameraImage::MONO8, std::string(6, 'x'), 2, 3)), "");
  EXPECT_NE(check(imageMessage(v1::CameraImage::MONO8, std::string(5, 'x'), 2, 3)), "");
  EXPECT_EQ(check(imageMessage(v1::CameraImage::RGB8, std::string(18, 'x'), 2, 3)), "");
  EXPECT_NE(check(imageMessage(v1::CameraImage::RGB8, std::string(6, 'x'), 2, 3)), "");
  EXPECT_NE(check(imageMessage(v1::CameraImage::MONO8, std::string(6, 'x'), 0, 6)), "");
}

TEST(CheckImage, RawSizeDoesNotWrapAround) {
  // 4294853786 × 1431693603 × 3 wraps to 41258 in 64 bits.
  const std::string problem =
      check(imageMessage(v1::CameraImage::RGB8, std::string(41258, 'x'), 4294853786u, 1431693603u));
  EXPECT_NE(problem.find("too large"), std::string::npos) << problem;
  // The largest MONO8 size does not overflow: it is refused for its data size only.
  EXPECT_NE(check(imageMessage(v1::CameraImage::MONO8, "x", UINT32_MAX, UINT32_MAX)).find("bytes"), std::string::npos);
}

TEST(CheckImage, RejectsNoDataUnknownEncodingAndBadPose) {
  EXPECT_NE(check(imageMessage(v1::CameraImage::JPEG, "")), "");
  EXPECT_NE(check(imageMessage(v1::CameraImage::ENCODING_UNSPECIFIED, "\xFF\xD8\xFF")), "");
  v1::RobotMessage m = imageMessage(v1::CameraImage::JPEG, "\xFF\xD8\xFF");
  setOrientation(*m.mutable_image()->mutable_camera_pose(), 0.0, 0.0, 0.9, 0.0);
  EXPECT_NE(check(m), "");
}

TEST(CheckOdometry, ChecksThePose) {
  v1::RobotMessage m;
  m.set_seq(3);
  m.mutable_odometry()->mutable_pose()->mutable_position_m()->set_x(2.0);
  EXPECT_EQ(check(m), "");
  m.mutable_odometry()->mutable_pose()->mutable_position_m()->set_z(std::nan(""));
  EXPECT_NE(check(m), "");
}

TEST(CheckDataMessage, RejectsSeqZeroHelloAndNoBody) {
  v1::RobotMessage seq0 = cloudMessage({1, 2, 3});
  seq0.set_seq(0);
  EXPECT_NE(check(seq0), "");
  v1::RobotMessage h;
  h.set_seq(1);
  *h.mutable_hello() = hello();
  EXPECT_NE(check(h), "");
  v1::RobotMessage empty;
  empty.set_seq(1);
  EXPECT_NE(check(empty), "");
}

TEST(CheckDataMessage, RefusesSeqAboveInt64Max) {
  v1::RobotMessage m = cloudMessage({1, 2, 3});
  m.set_seq(uint64_t{1} << 63);
  EXPECT_NE(check(m).find("seq"), std::string::npos) << check(m);
  m.set_seq(UINT64_MAX);
  EXPECT_NE(check(m), "");
  m.set_seq(static_cast<uint64_t>(INT64_MAX));
  EXPECT_EQ(check(m), "");
}

TEST(CheckCloud, RefusesASensorOriginOutsideTheAddressableRange) {
  // At 0.1 m the cells end at ±3276.8 m; the points may lie outside (they are dropped), the origin not.
  v1::RobotMessage m = cloudMessage({1, 2, 3, 5000, 0, 0});
  m.mutable_cloud()->set_frame(v1::PointCloud::MAP);
  v1::Vector3& origin = *m.mutable_cloud()->mutable_sensor_pose()->mutable_position_m();
  origin.set_x(3276.7);
  EXPECT_EQ(check(m), "");
  origin.set_x(3276.8);
  EXPECT_NE(check(m).find("outside the map's addressable range"), std::string::npos) << check(m);
  origin.set_x(0.0);
  origin.set_z(-1e300);  // finite in double, infinite as the float the map takes
  EXPECT_NE(check(m), "");
  // The range scales with the map's resolution.
  origin.set_z(5000.0);
  EXPECT_NE(check(m), "");
  EXPECT_EQ(checkDataMessage(m, LimitsConfig{}, map3d::Grid(1.0)), "");
}

TEST(DecodeRobotFrame, TheFirstFrameMustBeAValidHello) {
  v1::RobotMessage m;
  m.set_seq(7);
  *m.mutable_hello() = hello();
  const RobotFrame ok = decodeRobotFrame(m.SerializeAsString(), true, nullptr, LimitsConfig{});
  ASSERT_TRUE(ok.message) << ok.problem;
  EXPECT_EQ(ok.message->hello().robot_id(), "robot-1");
  EXPECT_EQ(ok.seq, 7u);

  m.mutable_hello()->set_robot_id("robot 1");
  const RobotFrame bad = decodeRobotFrame(m.SerializeAsString(), true, nullptr, LimitsConfig{});
  EXPECT_FALSE(bad.message);
  EXPECT_EQ(bad.code, "invalid_hello");
  EXPECT_TRUE(bad.fatal);

  const RobotFrame cloud = decodeRobotFrame(cloudMessage({1, 2, 3}).SerializeAsString(), true, nullptr, LimitsConfig{});
  EXPECT_EQ(cloud.code, "hello_required");
  EXPECT_EQ(cloud.seq, 1u);
  EXPECT_TRUE(cloud.fatal);
}

TEST(DecodeRobotFrame, DataFramesAreParsedAndChecked) {
  const map3d::Grid grid(0.1);
  const RobotFrame ok = decodeRobotFrame(cloudMessage({1, 2, 3}).SerializeAsString(), true, &grid, LimitsConfig{});
  ASSERT_TRUE(ok.message) << ok.problem;
  EXPECT_EQ(ok.message->cloud().xyz_m_size(), 3);

  const RobotFrame ragged = decodeRobotFrame(cloudMessage({1, 2}).SerializeAsString(), true, &grid, LimitsConfig{});
  EXPECT_EQ(ragged.code, "invalid_message");
  EXPECT_NE(ragged.problem.find("multiple of 3"), std::string::npos) << ragged.problem;
  EXPECT_EQ(ragged.seq, 1u);
  EXPECT_FALSE(ragged.fatal);

  const RobotFrame text = decodeRobotFrame(cloudMessage({1, 2, 3}).SerializeAsString(), false, &grid, LimitsConfig{});
  EXPECT_EQ(text.code, "invalid_message");
  EXPECT_NE(text.problem.find("binary"), std::string::npos) << text.problem;

  const RobotFrame garbage = decodeRobotFrame("\xFF\xFF\xFF", true, &grid, LimitsConfig{});
  EXPECT_EQ(garbage.code, "invalid_message");
  EXPECT_EQ(garbage.seq, 0u);
}

TEST(ToIsometry, AllZeroQuaternionIsIdentity) {
  v1::Pose3 pose;
  pose.mutable_position_m()->set_x(1.0);
  pose.mutable_position_m()->set_y(-2.0);
  pose.mutable_position_m()->set_z(3.0);
  const Eigen::Isometry3d t = toIsometry(pose);
  EXPECT_TRUE(t.linear().isIdentity(1e-12));
  EXPECT_TRUE(t.translation().isApprox(Eigen::Vector3d(1.0, -2.0, 3.0)));
}

TEST(ToIsometry, RotatesByTheQuaternion) {
  v1::Pose3 pose;
  setOrientation(pose, std::cos(M_PI / 4), 0.0, 0.0, std::sin(M_PI / 4));  // 90° about z
  const Eigen::Vector3d x = toIsometry(pose) * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(x.x(), 0.0, 1e-12);
  EXPECT_NEAR(x.y(), 1.0, 1e-12);
  EXPECT_NEAR(x.z(), 0.0, 1e-12);
}

TEST(CloudInMap, MapFramePointsAreUnchanged) {
  v1::PointCloud cloud = cloudMessage({1.5f, -2.0f, 0.25f, 3, 4, 5}).cloud();
  cloud.set_frame(v1::PointCloud::MAP);
  cloud.mutable_sensor_pose()->mutable_position_m()->set_x(10.0);
  setOrientation(*cloud.mutable_sensor_pose(), std::cos(M_PI / 4), 0.0, 0.0, std::sin(M_PI / 4));
  const CloudInMap in_map = cloudInMap(cloud);
  ASSERT_EQ(in_map.points_m.size(), 2u);
  EXPECT_EQ(in_map.points_m[0], Eigen::Vector3f(1.5f, -2.0f, 0.25f));
  EXPECT_EQ(in_map.points_m[1], Eigen::Vector3f(3, 4, 5));
  EXPECT_TRUE(in_map.sensor_pose.translation().isApprox(Eigen::Vector3d(10.0, 0.0, 0.0)));
}

TEST(CloudInMap, SensorFramePointsAreTransformedBySensorPose) {
  v1::PointCloud cloud = cloudMessage({1, 0, 0, 0, 2, 1}).cloud();
  cloud.set_frame(v1::PointCloud::SENSOR);
  v1::Pose3& pose = *cloud.mutable_sensor_pose();
  pose.mutable_position_m()->set_x(10.0);
  pose.mutable_position_m()->set_y(20.0);
  pose.mutable_position_m()->set_z(1.0);
  setOrientation(pose, std::cos(M_PI / 4), 0.0, 0.0, std::sin(M_PI / 4));  // yaw 90°: x → y, y → -x
  const CloudInMap in_map = cloudInMap(cloud);
  ASSERT_EQ(in_map.points_m.size(), 2u);
  EXPECT_TRUE(in_map.points_m[0].isApprox(Eigen::Vector3f(10.0f, 21.0f, 1.0f), 1e-6f)) << in_map.points_m[0];
  EXPECT_TRUE(in_map.points_m[1].isApprox(Eigen::Vector3f(8.0f, 20.0f, 2.0f), 1e-6f)) << in_map.points_m[1];
  EXPECT_TRUE(in_map.sensor_pose.translation().isApprox(Eigen::Vector3d(10.0, 20.0, 1.0)));
}

}  // namespace
}  // namespace rmap::app
