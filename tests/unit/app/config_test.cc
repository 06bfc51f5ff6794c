#include "app/config.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>

#include "app/slam2d_layer.h"
#include "rmap/v1/map_api.pb.h"

namespace rmap::app {
namespace {

/// A YAML file under the temporary directory, removed when the test ends.
class YamlFile {
 public:
  explicit YamlFile(const std::string& text) {
    static int counter = 0;
    path_ = std::filesystem::temp_directory_path() /
            ("rmap_app_config_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + ".yaml");
    std::ofstream(path_) << text;
  }
  ~YamlFile() { std::filesystem::remove(path_); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// The message of the runtime_error loadConfigFile throws for `text`, or "" when it does not throw.
std::string loadError(const std::string& text) {
  const YamlFile file(text);
  Config config;
  try {
    loadConfigFile(file.path(), config);
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(file.path().string()), std::string::npos) << message;
    return message;
  }
  return {};
}

TEST(LoadConfigFile, SetsEveryGivenKey) {
  const YamlFile file(R"(
listen: "0.0.0.0:9000"
data_dir: /var/lib/rmap
web_root: /usr/share/rmap/web
io_threads: 4
viewer_tick_ms: 50
auth:
  tokens:
    - {token: robot-secret-1, role: robot, robot_id: r1}
    - {token: viewer-secret, role: viewer}
    - {token: admin-secret, role: admin}
  allowed_origins: ["https://app.example"]
limits:
  max_frame_bytes: 1000
  max_points_per_cloud: 42
  max_messages_per_s_per_robot: 12.5
  max_memory_bytes: 536870912
maps:
  resolution_m: 0.05
  insert_threads: 3
  max_range_m: 30
  fusion_tolerance_log_odds: 0.5
)");
  Config config;
  loadConfigFile(file.path(), config);

  EXPECT_EQ(config.listen_host, "0.0.0.0");
  EXPECT_EQ(config.listen_port, 9000);
  EXPECT_EQ(config.data_dir, "/var/lib/rmap");
  EXPECT_EQ(config.web_root, "/usr/share/rmap/web");
  EXPECT_EQ(config.io_threads, 4);
  EXPECT_EQ(config.viewer_tick_ms, 50);
  ASSERT_EQ(config.auth.tokens.size(), 3u);
  EXPECT_EQ(config.auth.tokens[0].token, "robot-secret-1");
  EXPECT_EQ(config.auth.tokens[0].role, Role::kRobot);
  EXPECT_EQ(config.auth.tokens[0].robot_id, "r1");
  EXPECT_EQ(config.auth.tokens[1].role, Role::kViewer);
  EXPECT_EQ(config.auth.tokens[1].robot_id, "");
  EXPECT_EQ(config.auth.tokens[2].role, Role::kAdmin);
  EXPECT_EQ(config.auth.allowed_origins, std::vector<std::string>{"https://app.example"});
  EXPECT_EQ(config.limits.max_frame_bytes, 1000u);
  EXPECT_EQ(config.limits.max_points_per_cloud, 42u);
  EXPECT_EQ(config.limits.max_messages_per_s_per_robot, 12.5);
  EXPECT_EQ(config.limits.max_memory_bytes, 512u << 20);
  EXPECT_EQ(config.maps.resolution_m, 0.05);
  EXPECT_EQ(config.maps.insert_threads, 3);
  EXPECT_EQ(config.maps.occupancy.max_range_m, 30.0);
  EXPECT_FLOAT_EQ(config.maps.fusion.tolerance_log_odds, 0.5f);
}

TEST(LoadConfigFile, AbsentKeysKeepTheirValues) {
  const YamlFile file("io_threads: 3\nlimits:\n  max_body_bytes: 7\n");
  Config config;
  config.listen_port = 1234;
  config.auth.tokens.push_back({"kept-token", Role::kAdmin, ""});
  loadConfigFile(file.path(), config);

  const Config defaults;
  EXPECT_EQ(config.io_threads, 3);
  EXPECT_EQ(config.limits.max_body_bytes, 7u);
  EXPECT_EQ(config.listen_port, 1234);
  EXPECT_EQ(config.listen_host, defaults.listen_host);
  EXPECT_EQ(config.data_dir, defaults.data_dir);
  EXPECT_EQ(config.web_root, defaults.web_root);
  ASSERT_EQ(config.auth.tokens.size(), 1u);
  EXPECT_EQ(config.auth.tokens[0].token, "kept-token");
  EXPECT_EQ(config.limits.max_frame_bytes, defaults.limits.max_frame_bytes);
  EXPECT_EQ(config.maps.resolution_m, defaults.maps.resolution_m);
  EXPECT_EQ(config.snapshot_interval_s, defaults.snapshot_interval_s);
  EXPECT_EQ(config.limits.max_memory_bytes, 0u) << "no memory bound unless one is configured";
}

TEST(LoadConfigFile, BadRoleNamesTheFileAndTheRole) {
  const std::string message = loadError("auth:\n  tokens:\n    - {token: some-secret, role: superuser}\n");
  EXPECT_NE(message.find("superuser"), std::string::npos) << message;
}

TEST(LoadConfigFile, BadTypesThrowNamingTheFile) {
  EXPECT_NE(loadError("io_threads: many\n"), "");
  EXPECT_NE(loadError("limits:\n  max_frame_bytes: -1\n"), "");
  EXPECT_NE(loadError("limits:\n  max_memory_bytes: -1\n"), "");
  EXPECT_NE(loadError("limits:\n  max_memory_bytes: 2GiB\n"), "");
  EXPECT_NE(loadError("maps:\n  resolution_m: [1, 2]\n"), "");
  EXPECT_NE(loadError("auth:\n  tokens:\n    - {role: admin}\n").find("auth.tokens[].token is required"),
            std::string::npos);
  EXPECT_NE(loadError("auth:\n  tokens:\n    - {token: some-secret}\n").find("auth.tokens[].role is required"),
            std::string::npos);
  // Not a list: refused, where iterating it would have left no token at all.
  EXPECT_NE(loadError("auth:\n  tokens: 5\n").find("auth.tokens must be a list"), std::string::npos);
  EXPECT_NE(loadError("auth:\n  tokens: {token: some-secret, role: admin}\n").find("auth.tokens must be a list"),
            std::string::npos);
  // A value of the wrong kind names its key and its place.
  EXPECT_NE(loadError("maps:\n  resolution_m: abc\n").find("maps.resolution_m: a value of the wrong kind (line 2"),
            std::string::npos);
  EXPECT_NE(loadError("auth:\n  allowed_origins: 3\n").find("auth.allowed_origins: a value of the wrong kind"),
            std::string::npos);
  EXPECT_NE(loadError("listen: [1]\n").find("listen: a value of the wrong kind"), std::string::npos);
}

TEST(LoadConfigFile, BadListenAddressThrowsNamingTheFile) {
  const std::string message = loadError("listen: \"localhost:http\"\n");
  EXPECT_NE(message.find("listen"), std::string::npos) << message;
  EXPECT_NE(message.find("'http'"), std::string::npos) << message;
}

TEST(LoadConfigFile, MissingFileThrowsNamingIt) {
  Config config;
  const std::filesystem::path missing = std::filesystem::temp_directory_path() / "rmap_no_such_config.yaml";
  try {
    loadConfigFile(missing, config);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
  }
}

TEST(SetListenAddress, AcceptsHostAndPort) {
  Config config;
  setListenAddress("192.168.1.2:8081", config);
  EXPECT_EQ(config.listen_host, "192.168.1.2");
  EXPECT_EQ(config.listen_port, 8081);
  setListenAddress("localhost:65535", config);
  EXPECT_EQ(config.listen_host, "localhost");
  EXPECT_EQ(config.listen_port, 65535);
}

TEST(SetListenAddress, StripsTheBracketsOfIpv6) {
  Config config;
  setListenAddress("[::1]:8080", config);
  EXPECT_EQ(config.listen_host, "::1");
  EXPECT_EQ(config.listen_port, 8080);
}

TEST(SetListenAddress, AcceptsPortZero) {
  Config config;
  setListenAddress("0.0.0.0:0", config);
  EXPECT_EQ(config.listen_host, "0.0.0.0");
  EXPECT_EQ(config.listen_port, 0);
}

TEST(SetListenAddress, RejectsMalformedAddressesAndKeepsTheConfig) {
  for (const std::string bad : {"", "8080", ":8080", "host:", "host:http", "host:65536", "host:-1", "host:80x",
                                "[::1]", "host:99999999999"}) {
    Config config;
    EXPECT_THROW(setListenAddress(bad, config), std::invalid_argument) << bad;
    EXPECT_EQ(config.listen_host, Config{}.listen_host) << bad;
    EXPECT_EQ(config.listen_port, Config{}.listen_port) << bad;
  }
}

TEST(SetListenAddress, RejectsUnbalancedOrEmptyBrackets) {
  for (const std::string bad : {"[::1:8080", "::1]:8080", "[]:8080", "[:8080", "]:8080", "[[::1]]:8080",
                                "[::1]x:8080", "::1:8080", "[::1]]:8080"}) {
    Config config;
    EXPECT_THROW(setListenAddress(bad, config), std::invalid_argument) << bad;
    EXPECT_EQ(config.listen_host, Config{}.listen_host) << bad;
    EXPECT_EQ(config.listen_port, Config{}.listen_port) << bad;
  }
}

TEST(Validate, AcceptsTheDefaults) {
  const Config defaults;
  EXPECT_NO_THROW(validate(defaults));
}

TEST(Validate, RejectsAnEmptyWebRoot) {
  Config config;
  config.web_root.clear();
  EXPECT_THROW(validate(config), std::invalid_argument);
}

TEST(DefaultWebRoot, IsTheBuildsWebDirectory) {
  // CMake sets RMAP_WEB_ROOT to the source tree's web/ unless told otherwise.
  EXPECT_TRUE(defaultWebRoot().is_absolute()) << defaultWebRoot();
  const Config defaults;
  EXPECT_EQ(defaults.web_root, defaultWebRoot());
}

TEST(Validate, RejectsARobotTokenWithoutRobotId) {
  Config config;
  config.auth.tokens.push_back({"robot-secret", Role::kRobot, ""});
  EXPECT_THROW(validate(config), std::invalid_argument);
  config.auth.tokens.back().robot_id = "r1";
  EXPECT_NO_THROW(validate(config));
}

TEST(Validate, RejectsShortTokens) {
  Config config;
  config.auth.tokens.push_back({"1234567", Role::kViewer, ""});
  EXPECT_THROW(validate(config), std::invalid_argument);
  config.auth.tokens.back().token = "12345678";
  EXPECT_NO_THROW(validate(config));
}

TEST(Validate, RejectsBadResolutions) {
  for (const double resolution : {0.0, -0.1, double(NAN), double(INFINITY)}) {
    Config config;
    config.maps.resolution_m = resolution;
    EXPECT_THROW(validate(config), std::invalid_argument) << resolution;
  }
}

/// Whether validate() refuses the defaults changed by `change`.
bool refused(const std::function<void(Config&)>& change) {
  Config config;
  change(config);
  try {
    validate(config);
  } catch (const std::invalid_argument&) {
    return true;
  }
  return false;
}

TEST(Validate, RejectsBadCounts) {
  EXPECT_TRUE(refused([](Config& c) { c.io_threads = 0; }));
  EXPECT_TRUE(refused([](Config& c) { c.maps.insert_threads = 0; }));
  EXPECT_TRUE(refused([](Config& c) { c.viewer_tick_ms = 9; }));
  EXPECT_TRUE(refused([](Config& c) { c.log_level = "verbose"; }));
}

TEST(Validate, ZeroSizeLimitsAreRefusedNotReadAsUnlimited) {
  for (size_t LimitsConfig::*limit :
       {&LimitsConfig::max_frame_bytes, &LimitsConfig::max_body_bytes, &LimitsConfig::max_points_per_cloud,
        &LimitsConfig::max_batch_points, &LimitsConfig::max_in_flight_per_robot,
        &LimitsConfig::viewer_send_queue_bytes, &LimitsConfig::max_box_cuboids}) {
    Config config;
    config.limits.*limit = 0;
    EXPECT_THROW(validate(config), std::invalid_argument);
  }
}

TEST(Validate, ABatchOfMaxBatchPointsMustFitInTheBodyLimit) {
  Config config;
  for (const size_t points : {size_t{1}, size_t{5}, size_t{1000}, size_t{100000}}) {
    v1::OccupancyBatchRequest request;
    for (size_t i = 0; i < 3 * points; ++i) request.add_xyz_m(1.5);
    EXPECT_EQ(batchRequestBytes(points), request.ByteSizeLong()) << points;
    config.limits.max_batch_points = points;
    config.limits.max_body_bytes = request.ByteSizeLong();
    EXPECT_NO_THROW(validate(config)) << points;
    config.limits.max_body_bytes -= 1;
    EXPECT_THROW(validate(config), std::invalid_argument) << points;
  }
  EXPECT_EQ(batchRequestBytes(0), 0u);
  // 240 MB of doubles against 64 MiB
  EXPECT_TRUE(refused([](Config& c) { c.limits.max_batch_points = 10'000'000; }));
  EXPECT_TRUE(refused([](Config& c) { c.limits.max_batch_points = SIZE_MAX; }));
}

TEST(LoadConfigFile, ReadsTheTlsFiles) {
  const YamlFile file("tls:\n  certificate_file: /etc/rmap/cert.pem\n  private_key_file: /etc/rmap/key.pem\n");
  Config config;
  EXPECT_FALSE(config.tls.enabled());
  loadConfigFile(file.path(), config);
  EXPECT_TRUE(config.tls.enabled());
  EXPECT_EQ(config.tls.certificate_file, "/etc/rmap/cert.pem");
  EXPECT_EQ(config.tls.private_key_file, "/etc/rmap/key.pem");
  EXPECT_NO_THROW(validate(config));  // the files themselves are read when the server starts
}

TEST(Validate, TlsNeedsBothFiles) {
  for (const bool with_certificate : {true, false}) {
    Config config;
    (with_certificate ? config.tls.certificate_file : config.tls.private_key_file) = "/etc/rmap/file.pem";
    try {
      validate(config);
      ADD_FAILURE() << "half a TLS config was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_STREQ(e.what(), "tls needs both certificate_file and private_key_file");
    }
  }
}

TEST(RoleToString, NamesEveryRole) {
  EXPECT_STREQ(toString(Role::kRobot), "robot");
  EXPECT_STREQ(toString(Role::kViewer), "viewer");
  EXPECT_STREQ(toString(Role::kAdmin), "admin");
}

}  // namespace
}  // namespace rmap::app

namespace rmap::app {
namespace {

TEST(Slam2dCalibrations, FilesPerModelAreReadAndParsed) {
  const slam2d::IntensityCalibration calibration({std::log(0.5), std::log(20.0), {1.0, 1.0, 1.0, 1.0}},
                                                 {0.0, 80.0, {0.0, 0.0, 0.0, 0.0}}, 1000.0, 1.0);
  const YamlFile file(calibration.toText());
  const YamlFile config_file("slam2d:\n  calibrations:\n    sick_like: " + file.path().string() + "\n");
  Config config;
  loadConfigFile(config_file.path(), config);
  ASSERT_EQ(config.slam2d.calibration_files.size(), 1u);
  EXPECT_EQ(config.slam2d.calibration_files.at("sick_like"), file.path());
  const Calibrations loaded = loadCalibrations(config.slam2d);
  ASSERT_EQ(loaded.size(), 1u);
  EXPECT_EQ(loaded.at("sick_like").toText(), calibration.toText());
  EXPECT_NO_THROW(validate(config));
}

TEST(Slam2dCalibrations, AMissingOrBadFileIsRefusedNamingTheModel) {
  Config config;
  config.slam2d.calibration_files["utm"] = "/nonexistent/utm.calib";
  try {
    validate(config);
    ADD_FAILURE() << "a missing calibration file was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("model 'utm'"), std::string::npos) << e.what();
  }
  const YamlFile bad("rmap_intensity_calibration 1\nrange_m 5 1\n");
  config.slam2d.calibration_files["utm"] = bad.path();
  EXPECT_THROW(validate(config), std::invalid_argument);
}

TEST(Slam2dOptions, TheFileSetsTheTunedOptionsAndKeepsTheRest) {
  const YamlFile file(R"(
slam2d:
  resolution_m: 0.1
  range_min_m: 0.3
  range_max_m: 12
  use_odometry: false
  map_update_distance_m: 0.4
  map_update_angle_rad: 0.2
  reflectivity_weight: 0.5
  self_calibration: false
  relock_after_large_step_m: 0.6
  loop_closure:
    enabled: false
    min_score: 0.62
    sparse_min_score: 0.75
    sparse_loop_edge_keyframes: 1
    member_check_exclusion_m: -1
    member_check_near_exclusion_m: 0
    member_check_max_turn_rad: 0.08
    member_check_max_shift_m: 0.35
    ambiguity_margin: 0.2
    ambiguous_min_score: 0.7
    support_min_separation_m: 0.5
    min_match_points: 20
    max_window_m: 3
    max_window_rad: 0.5
    confirm_after_s: 0
    rerender_checkpoints: 0
)");
  Config config;
  loadConfigFile(file.path(), config);
  const slam2d::Slam2dOptions& o = config.slam2d.options;
  const slam2d::Slam2dOptions defaults;
  EXPECT_EQ(o.resolution_m, 0.1);
  EXPECT_EQ(o.range_min_m, 0.3f);
  EXPECT_EQ(o.range_max_m, 12.0f);
  EXPECT_FALSE(o.use_odometry);
  EXPECT_EQ(o.map_update_distance_m, 0.4);
  EXPECT_EQ(o.map_update_angle_rad, 0.2);
  EXPECT_EQ(o.reflectivity_weight, 0.5);
  EXPECT_FALSE(o.self_calibration);
  EXPECT_EQ(o.relock_after_large_step_m, 0.6);
  EXPECT_FALSE(o.loop_closure.enabled);
  EXPECT_EQ(o.loop_closure.min_score, 0.62);
  EXPECT_EQ(o.loop_closure.sparse_min_score, 0.75);
  EXPECT_EQ(o.loop_closure.sparse_loop_edge_keyframes, 1);
  EXPECT_EQ(o.loop_closure.member_check_exclusion_m, -1.0);
  EXPECT_EQ(o.loop_closure.member_check_near_exclusion_m, 0.0);
  EXPECT_EQ(o.loop_closure.member_check_max_turn_rad, 0.08);
  EXPECT_EQ(o.loop_closure.member_check_max_shift_m, 0.35);
  EXPECT_EQ(o.loop_closure.submap.ambiguity_margin, 0.2);
  EXPECT_EQ(o.loop_closure.ambiguous_min_score, 0.7);
  EXPECT_EQ(o.loop_closure.support_min_separation_m, 0.5);
  EXPECT_EQ(o.loop_closure.min_match_points, 20);
  EXPECT_EQ(o.loop_closure.max_window_m, 3.0);
  EXPECT_EQ(o.loop_closure.max_window_rad, 0.5);
  EXPECT_EQ(o.loop_closure.confirm_after_s, 0.0);
  EXPECT_EQ(o.loop_closure.rerender_checkpoints, 0);
  EXPECT_EQ(o.levels, defaults.levels);
  EXPECT_EQ(o.loop_closure.submap_keyframes, defaults.loop_closure.submap_keyframes);
  EXPECT_NO_THROW(validate(config));
}

TEST(Slam2dOptions, BadValuesAreRefusedNamingTheSection) {
  for (const char* text : {"slam2d:\n  resolution_m: 0\n", "slam2d:\n  range_max_m: -1\n",
                           "slam2d:\n  loop_closure:\n    min_score: 1.5\n",
                           "slam2d:\n  loop_closure:\n    confirm_after_s: -1\n",
                           "slam2d:\n  loop_closure:\n    min_match_points: -1\n",
                           "slam2d:\n  loop_closure:\n    rerender_checkpoints: -2\n",
                           "slam2d:\n  loop_closure:\n    ambiguity_margin: .nan\n",
                           "slam2d:\n  loop_closure:\n    member_check_max_shift_m: -0.1\n",
                           "slam2d:\n  loop_closure:\n    member_check_max_turn_rad: 4\n",
                           "slam2d:\n  loop_closure:\n    member_check_near_exclusion_m: .nan\n",
                           "slam2d:\n  relock_after_large_step_m: -0.5\n"}) {
    const YamlFile file(text);
    Config config;
    loadConfigFile(file.path(), config);
    try {
      validate(config);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind("slam2d: ", 0), 0u) << e.what();
    }
  }
}

TEST(LoadConfigFile, UnknownKeysAreRefusedWithTheirPath) {
  // A misspelt key would otherwise leave its default in place without a word.
  EXPECT_NE(loadError("io_thread: 4\n").find("unknown key 'io_thread'"), std::string::npos);
  EXPECT_NE(loadError("limits:\n  max_frame_byte: 10\n").find("unknown key 'limits.max_frame_byte'"),
            std::string::npos);
  EXPECT_NE(loadError("maps:\n  resolution: 0.2\n").find("'maps.resolution'"), std::string::npos);
  EXPECT_NE(loadError("auth:\n  tokens:\n    - {token: some-secret, role: admin, robot: r1}\n")
                .find("'auth.tokens[].robot'"),
            std::string::npos);
  EXPECT_NE(loadError("tls:\n  certificate: a.pem\n").find("'tls.certificate'"), std::string::npos);
  EXPECT_NE(loadError("loop_closure:\n  cameras: false\n").find("'loop_closure.cameras'"), std::string::npos);
  EXPECT_NE(loadError("slam2d:\n  loop_closure:\n    min_scor: 0.7\n").find("'slam2d.loop_closure.min_scor'"),
            std::string::npos);
  EXPECT_NE(loadError("slam2d: 3\n").find("slam2d must be a mapping"), std::string::npos);
  EXPECT_NE(loadError("slam2d:\n  loop_closure: [1]\n").find("slam2d.loop_closure must be a mapping"),
            std::string::npos);
  EXPECT_NE(loadError("- 1\n").find("the file must be a mapping"), std::string::npos);
  EXPECT_EQ(loadError(""), "") << "an empty file sets nothing";
  EXPECT_EQ(loadError("limits:\n"), "") << "an empty section sets nothing";
}

}  // namespace
}  // namespace rmap::app
