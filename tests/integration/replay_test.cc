// `rmap replay` end to end: for each format the test writes a small dataset of a wall seen
// from two sensor poses, replays it with the real CLI into a real rmapd and asks the map
// what it knows: the wall occupied, the space in front of it free, behind it unknown. A CARMEN
// log of a box room gives the 2D layer and its raster tile. Bad files are refused, named, and
// change nothing.
#include <gtest/gtest.h>
#include <png.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <thread>

#include "api_helpers.h"
#include "client/http_client.h"
#include "rmap_cli.h"
#include "rmapd_process.h"

namespace rmap::testing {
namespace {

namespace fs = std::filesystem;

/// Runs `rmap replay ARGS` and captures its exit code and output.
CliRun replay(const fs::path& dir, const std::string& args) { return runRmap("replay " + args, dir); }

/// The scene: a wall at x = 3.05 m (y −1…1 m, z 0…1 m, 5 cm apart) seen by two sensor poses.
std::vector<Eigen::Vector3d> wallPoints() {
  std::vector<Eigen::Vector3d> points;
  for (int j = 0; j <= 40; ++j)
    for (int k = 0; k <= 20; ++k) points.emplace_back(3.05, -1.0 + 0.05 * j, 0.05 * k);
  return points;
}

Eigen::Isometry3d sensorPose(int i) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  if (i == 0) {
    pose.translation() = Eigen::Vector3d(0.0, 0.0, 0.5);
  } else {
    pose.translation() = Eigen::Vector3d(0.3, -0.2, 0.5);
    pose.linear() = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  }
  return pose;
}

/// The wall in the sensor frame of pose i.
std::vector<Eigen::Vector3d> sensorPoints(int i) {
  std::vector<Eigen::Vector3d> out;
  for (const Eigen::Vector3d& p : wallPoints()) out.push_back(sensorPose(i).inverse() * p);
  return out;
}

std::string kittiPoseLine(const Eigen::Isometry3d& p) {
  std::ostringstream line;
  line.precision(17);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) line << (r || c ? " " : "") << p.matrix()(r, c);
  return line.str() + "\n";
}

std::string tumPoseLine(double stamp_s, const Eigen::Isometry3d& p) {
  const Eigen::Quaterniond q(p.linear());
  std::ostringstream line;
  line.precision(17);
  line << stamp_s << ' ' << p.translation().x() << ' ' << p.translation().y() << ' ' << p.translation().z() << ' '
       << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << "\n";
  return line.str();
}

template <class T>
void put(std::string& out, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof v);
  out.append(b, sizeof b);
}

/// An OctoMap ScanGraph file (layout of datasets/octomap_graph.h) of both poses.
std::string graphBytes() {
  std::string out;
  put(out, uint32_t{2});
  for (int i = 0; i < 2; ++i) {
    const std::vector<Eigen::Vector3d> points = sensorPoints(i);
    put(out, static_cast<uint32_t>(points.size()));
    for (const Eigen::Vector3d& p : points) {
      put(out, int32_t{3});
      for (int a = 0; a < 3; ++a) put(out, p[a]);
    }
    const Eigen::Isometry3d pose = sensorPose(i);
    const Eigen::Quaterniond q(pose.linear());
    put(out, int32_t{3});
    for (int a = 0; a < 3; ++a) put(out, pose.translation()[a]);
    put(out, int32_t{4});
    for (const double v : {q.w(), q.x(), q.y(), q.z()}) put(out, v);
    put(out, static_cast<uint32_t>(i));
  }
  put(out, uint32_t{0});
  return out;
}

std::string pngBytes(int width, int height, uint8_t shade) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  image.width = static_cast<png_uint_32>(width);
  image.height = static_cast<png_uint_32>(height);
  image.format = PNG_FORMAT_GRAY;
  std::vector<uint8_t> pixels(static_cast<size_t>(width * height));
  for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<uint8_t>(shade + (i % 7) * 20);
  png_alloc_size_t size = 0;
  png_image_write_to_memory(&image, nullptr, &size, 0, pixels.data(), 0, nullptr);
  std::string out(size, '\0');
  EXPECT_TRUE(png_image_write_to_memory(&image, out.data(), &size, 0, pixels.data(), 0, nullptr));
  out.resize(size);
  return out;
}

/// A CARMEN log of a robot driving 0.5 m along x in a box room (x −1.55…3.05, y −2.05…2.55),
/// 181 beams over 180°, raw-log style (ODOM lines run on) so its poses are the odometry.
std::string boxRoomLog() {
  std::ostringstream log;
  log.precision(9);
  for (int k = 0; k < 6; ++k) {
    const double x = 0.1 * k, y = 0.0, th = 0.0;
    const double stamp = 100.0 + 0.2 * k;
    log << "ODOM " << x << ' ' << y << ' ' << th << " 0 0 0 " << stamp - 0.05 << " host " << stamp - 0.05 << "\n";
    log << "FLASER 181";
    for (int i = 0; i < 181; ++i) {
      const double a = th - std::numbers::pi / 2 + i * std::numbers::pi / 180;
      const double dx = std::cos(a), dy = std::sin(a);
      double t = 1e9;
      if (dx > 1e-12) t = std::min(t, (3.05 - x) / dx);
      if (dx < -1e-12) t = std::min(t, (-1.55 - x) / dx);
      if (dy > 1e-12) t = std::min(t, (2.55 - y) / dy);
      if (dy < -1e-12) t = std::min(t, (-2.05 - y) / dy);
      log << ' ' << t;
    }
    log << ' ' << x << ' ' << y << ' ' << th << ' ' << x << ' ' << y << ' ' << th << ' ' << stamp << " host " << stamp
        << "\n";
  }
  return log.str();
}

class ReplayTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    data_ = std::make_unique<TempDir>("rmap_replay_rmapd");
    rmapd_ = std::make_unique<RmapdProcess>(data_->path() / "data");  // its log beside it, inside the temporary folder
  }
  static void TearDownTestSuite() {
    rmapd_.reset();
    data_.reset();
  }
  void SetUp() override { dir_ = std::make_unique<TempDir>("rmap_replay_files"); }

  fs::path write(const std::string& name, const std::string& content) {
    const fs::path p = dir_->path() / name;
    fs::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary) << content;
    return p;
  }
  std::string args(const std::string& map) const {
    return "--server " + rmapd_->wsUrl() + " --map " + map + " --resolution 0.1 --json " +
           (dir_->path() / "summary.json").string();
  }
  nlohmann::json summary() const { return nlohmann::json::parse(fileText(dir_->path() / "summary.json")); }

  /// Replays and expects success with `frames` acknowledged messages.
  void expectReplayed(const std::string& command, size_t frames) {
    const CliRun run = replay(dir_->path(), command);
    ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
    const nlohmann::json s = summary();
    EXPECT_EQ(s["messages_acked"], frames) << run.out;
    EXPECT_EQ(s["errors"], 0);
    EXPECT_NE(run.out.find("replay complete"), std::string::npos) << run.out;
    EXPECT_NE(run.err.find("100%"), std::string::npos) << run.err;  // the progress, plain lines off a TTY
  }

  /// The wall occupied, the space before it free, behind it unknown.
  void expectWall(const std::string& map) {
    client::HttpClient http(rmapd_->httpUrl());
    const std::string base = "/v1/maps/" + map + "/occupancy?";
    EXPECT_EQ(getJson(http, base + "x=3.05&y=0.05&z=0.55")["state"], "occupied") << map;
    EXPECT_EQ(getJson(http, base + "x=3.05&y=-0.75&z=0.15")["state"], "occupied") << map;
    EXPECT_EQ(getJson(http, base + "x=1.5&y=0.05&z=0.55")["state"], "free") << map;
    EXPECT_EQ(getJson(http, base + "x=5.05&y=0.05&z=0.55")["state"], "unknown") << map;
    EXPECT_EQ(getJson(http, "/v1/maps/" + map)["resolution_m"], 0.1);
  }

  static std::unique_ptr<TempDir> data_;
  static std::unique_ptr<RmapdProcess> rmapd_;
  std::unique_ptr<TempDir> dir_;
};

std::unique_ptr<TempDir> ReplayTest::data_;
std::unique_ptr<RmapdProcess> ReplayTest::rmapd_;

/// The wall as a scan.dat-style text with a NODE line per pose.
std::string wallXyzText() {
  std::ostringstream text;
  for (int i = 0; i < 2; ++i) {
    const Eigen::Isometry3d pose = sensorPose(i);
    text << "NODE " << pose.translation().x() << ' ' << pose.translation().y() << ' ' << pose.translation().z()
         << " 0 0 " << (i ? 0.2 : 0.0) << "\n";
    for (const Eigen::Vector3d& p : sensorPoints(i)) text << p.x() << ' ' << p.y() << ' ' << p.z() << "\n";
  }
  return text.str();
}

TEST_F(ReplayTest, XyzTextWithNodes) {
  const fs::path file = write("wall.dat", wallXyzText());
  expectReplayed(args("xyz") + " " + file.string(), 2);
  EXPECT_EQ(summary()["points"], 2 * wallPoints().size());
  expectWall("xyz");
}

TEST_F(ReplayTest, OctomapGraph) {
  const fs::path file = write("wall.graph", graphBytes());
  expectReplayed(args("graph") + " " + file.string(), 2);
  expectWall("graph");
}

TEST_F(ReplayTest, VelodyneBinWithKittiPoses) {
  std::string poses;
  for (int i = 0; i < 2; ++i) {
    std::string bin;
    for (const Eigen::Vector3d& p : sensorPoints(i)) {
      for (int a = 0; a < 3; ++a) put(bin, static_cast<float>(p[a]));
      put(bin, 0.5f);
    }
    write("velodyne/00000" + std::to_string(i) + ".bin", bin);
    poses += kittiPoseLine(sensorPose(i));
  }
  const fs::path pose_file = write("poses.txt", poses);
  expectReplayed(args("kitti") + " --poses " + pose_file.string() + " " + (dir_->path() / "velodyne").string(), 2);
  expectWall("kitti");
  // Named after the folder.
  client::HttpClient http(rmapd_->httpUrl());
  EXPECT_EQ(getJson(http, "/v1/robots/velodyne")["map"], "kitti");
}

TEST_F(ReplayTest, PlyWithIntensityAndKittiPoses) {
  std::string poses;
  std::vector<std::string> files;
  for (int i = 0; i < 2; ++i) {
    const std::vector<Eigen::Vector3d> points = sensorPoints(i);
    std::ostringstream ply;
    ply << "ply\nformat ascii 1.0\nelement vertex " << points.size()
        << "\nproperty float x\nproperty float y\nproperty float z\nproperty float intensity\nend_header\n";
    for (const Eigen::Vector3d& p : points) ply << p.x() << ' ' << p.y() << ' ' << p.z() << " 12\n";
    files.push_back(write("cloud" + std::to_string(i) + ".ply", ply.str()).string());
    poses += kittiPoseLine(sensorPose(i));
  }
  const fs::path pose_file = write("poses.txt", poses);
  expectReplayed(args("ply") + " --robot plybot --poses " + pose_file.string() + " " + files[0] + " " + files[1], 2);
  expectWall("ply");
}

TEST_F(ReplayTest, BinaryPcdWithTumPoses) {
  std::string poses;
  for (int i = 0; i < 2; ++i) {
    const std::vector<Eigen::Vector3d> points = sensorPoints(i);
    std::string pcd = "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n"
                      "WIDTH " + std::to_string(points.size()) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " +
                      std::to_string(points.size()) + "\nDATA binary\n";
    for (const Eigen::Vector3d& p : points) {
      for (int a = 0; a < 3; ++a) put(pcd, static_cast<float>(p[a]));
      put(pcd, 3.0f);
    }
    write("pcd/" + std::to_string(i) + ".pcd", pcd);
    poses += tumPoseLine(10.0 + 0.5 * i, sensorPose(i));
  }
  const fs::path pose_file = write("poses.tum", poses);
  expectReplayed(args("pcd") + " --rate realtime --poses " + pose_file.string() + " " + (dir_->path() / "pcd").string(),
                 2);
  EXPECT_GE(summary()["duration_s"].get<double>(), 0.5);  // real time: the stamps are 0.5 s apart
  expectWall("pcd");
}

TEST_F(ReplayTest, Uos3dtkFolder) {
  // uos frame: centimetres, x right, y up, z forward; the scanner 50 cm above the origin.
  std::ostringstream scan;
  for (const Eigen::Vector3d& p : wallPoints()) scan << -p.y() * 100 << ' ' << p.z() * 100 - 50 << ' ' << p.x() * 100 << "\n";
  write("uos/scan000.3d", scan.str());
  write("uos/scan000.pose", "0 50 0\n0 0 0\n");
  expectReplayed(args("3dtk") + " " + (dir_->path() / "uos").string(), 1);
  expectWall("3dtk");
}

TEST_F(ReplayTest, ImageFolderWithPoses) {
  write("camera/000.png", pngBytes(32, 24, 30));
  write("camera/001.png", pngBytes(32, 24, 90));
  const fs::path pose_file = write("poses.txt", kittiPoseLine(sensorPose(0)) + kittiPoseLine(sensorPose(1)));
  expectReplayed(args("images") + " --poses " + pose_file.string() + " " + (dir_->path() / "camera").string(), 2);
  EXPECT_EQ(summary()["images"], 2);
  client::HttpClient http(rmapd_->httpUrl());
  const nlohmann::json robot = getJson(http, "/v1/robots/camera");
  EXPECT_NEAR(robot["pose"]["position"][0].get<double>(), 0.3, 1e-9);  // the last image's camera pose
  EXPECT_NEAR(robot["pose"]["position"][1].get<double>(), -0.2, 1e-9);
}

TEST_F(ReplayTest, CarmenLogGivesThe2dLayerAndPlanarMap) {
  const fs::path log = write("room.log", boxRoomLog());
  expectReplayed("--server " + rmapd_->wsUrl() + " --map room --json " + (dir_->path() / "summary.json").string() +
                     " " + log.string(),
                 6);
  EXPECT_EQ(summary()["scans"], 6);
  client::HttpClient http(rmapd_->httpUrl());
  // The planar cloud at the laser's height (0): walls occupied, the room free, above it unknown.
  EXPECT_EQ(getJson(http, "/v1/maps/room/occupancy?x=3.05&y=0.05&z=0.05")["state"], "occupied");
  EXPECT_EQ(getJson(http, "/v1/maps/room/occupancy?x=0.55&y=2.55&z=0.05")["state"], "occupied");
  EXPECT_EQ(getJson(http, "/v1/maps/room/occupancy?x=1.55&y=0.55&z=0.05")["state"], "free");
  EXPECT_EQ(getJson(http, "/v1/maps/room/occupancy?x=1.55&y=0.55&z=1.05")["state"], "unknown");
  const client::HttpResponse tile = http.get("/v1/maps/room/layers/occupancy/0/0/0.png");
  EXPECT_EQ(tile.status, 200);
  EXPECT_EQ(tile.header("content-type"), "image/png");
  EXPECT_EQ(tile.body.substr(0, 4), "\x89PNG");
  // The SLAM kept the robot on its odometry: the last pose 0.5 m along x.
  const nlohmann::json robot = getJson(http, "/v1/robots/room");
  EXPECT_NEAR(robot["pose"]["position"][0].get<double>(), 0.5, 0.05);
}

TEST_F(ReplayTest, MalformedFileIsNamedAndSendsNothing) {
  const fs::path log = write("broken.log", boxRoomLog() + "FLASER 3 1.0 2.0\n");
  const CliRun run = replay(dir_->path(), args("broken") + " " + log.string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("broken.log:13"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("nothing was sent"), std::string::npos) << run.err;
  client::HttpClient http(rmapd_->httpUrl());
  EXPECT_EQ(http.get("/v1/maps/broken").status, 404);

  const CliRun missing = replay(dir_->path(), args("broken") + " " + (dir_->path() / "nope.ply").string());
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("nope.ply: no such file"), std::string::npos) << missing.err;
  const CliRun bad_format = replay(dir_->path(), args("broken") + " --format las " + log.string());
  EXPECT_EQ(bad_format.exit_code, 2) << bad_format.err;
}

TEST_F(ReplayTest, BadFrameMidStreamStopsBeforeIt) {
  std::string good;
  for (const Eigen::Vector3d& p : wallPoints()) {
    for (int a = 0; a < 3; ++a) put(good, static_cast<float>(p[a]));
    put(good, 1.0f);
  }
  write("frames/0.bin", good);
  write("frames/1.bin", good.substr(0, 21));
  const CliRun run = replay(dir_->path(), args("partial") + " " + (dir_->path() / "frames").string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.out.find("1.bin: 21 bytes"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("frame 2 of 2 not sent"), std::string::npos) << run.out;
  const nlohmann::json s = summary();
  EXPECT_EQ(s["messages_sent"], 1);
  EXPECT_EQ(s["messages_acked"], 1);
  EXPECT_FALSE(s["ok"].get<bool>());
}

TEST_F(ReplayTest, RefusedMessagesFailTheReplay) {
  // A sensor origin outside the map's addressable range (±3276.8 m at 0.1 m): the server refuses the cloud.
  const fs::path file = write("far.dat", "NODE 5000 0 0 0 0 0\n1 0 0\n");
  const CliRun run = replay(dir_->path(), args("far") + " " + file.string());
  EXPECT_EQ(run.exit_code, 1) << run.out;
  const nlohmann::json s = summary();
  EXPECT_EQ(s["errors"], 1);
  EXPECT_EQ(s["messages_acked"], 0);
  EXPECT_NE(run.out.find("server error: invalid_message"), std::string::npos) << run.out;
}
#ifdef RMAP_BENCH_PATH
/// `rmap-bench replay-check ARGS` against the test's rmapd: its exit code, stdout in `out`.
int replayCheck(const fs::path& dir, const std::string& args, std::string& out) {
  const fs::path file = dir / "check.out";
  const std::string command = std::string(RMAP_BENCH_PATH) + " replay-check " + args + " >" + file.string() + " 2>&1";
  const int status = std::system(command.c_str());
  out = fileText(file);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The small version of bench/replay_equivalence.sh: the replayed maps are the offline builds.
TEST_F(ReplayTest, ReplayedMapsEqualTheOfflineBuilds) {
  const fs::path wall = write("wall.dat", wallXyzText());
  expectReplayed(args("eq3d") + " " + wall.string(), 2);
  const fs::path log = write("room.log", boxRoomLog());
  expectReplayed("--server " + rmapd_->wsUrl() + " --map eq2d --robot eqroom --json " + (dir_->path() / "summary.json").string() +
                     " " + log.string(),
                 6);
  std::this_thread::sleep_for(std::chrono::milliseconds(800));  // trajectory poses are written every 0.5 s
  std::string out;
  EXPECT_EQ(replayCheck(dir_->path(), "--server " + rmapd_->httpUrl() + " --map eq3d --resolution 0.1 --grid-step 1 --scans " +
                                          wall.string(), out), 0) << out;
  EXPECT_NE(out.find("-> EQUAL"), std::string::npos) << out;
  EXPECT_EQ(replayCheck(dir_->path(), "--server " + rmapd_->httpUrl() + " --map eq2d --robot eqroom --log " + log.string(), out), 0)
      << out;
  EXPECT_NE(out.find("PGM"), std::string::npos) << out;
  // And it can tell maps apart: the wall is not the room.
  EXPECT_EQ(replayCheck(dir_->path(), "--server " + rmapd_->httpUrl() + " --map eq2d --resolution 0.1 --scans " + wall.string(), out), 1)
      << out;
}

TEST_F(ReplayTest, ScanDatEqualsTheOfflineBuild) {
  const std::string scans = std::string(RMAP_SHARED_DATA_DIR) + "/octomap/scan.dat.bz2";
  if (!fs::exists(scans)) GTEST_SKIP() << scans << " not found";
  expectReplayed("--server " + rmapd_->wsUrl() + " --map scandat --resolution 0.1 --json " +
                     (dir_->path() / "summary.json").string() + " " + scans,
                 1);
  std::string out;
  EXPECT_EQ(replayCheck(dir_->path(), "--server " + rmapd_->httpUrl() + " --map scandat --resolution 0.1 --scans " + scans, out), 0)
      << out;
}
#endif

}  // namespace
}  // namespace rmap::testing
