#include "app/mapping_service.h"

#include <gtest/gtest.h>

#include <future>
#include <nlohmann/json.hpp>

#include "same_grey_recognizer.h"
#include "service_test_support.h"

namespace rmap::app {
namespace {

/// Logs `message` of robot "bot" for map "lab" straight into the store.
void logMessage(store::Store& store, const v1::RobotMessage& message) {
  store::MessageRecord record{"lab", "bot", message.seq(), static_cast<int32_t>(message.body_case()), 1,
                              message.SerializeAsString()};
  ASSERT_FALSE(store.append({&record, 1}).at(0).duplicate);
}

TEST(MappingService, EpochGrowsWithEveryStart) {
  store::TempDir dir;
  int64_t first = 0;
  {
    const MappingService service(testing::configIn(dir.path()));
    first = service.epoch();
    EXPECT_GT(first, 0);
  }
  const MappingService service(testing::configIn(dir.path()));
  EXPECT_GT(service.epoch(), first);
}

TEST(MappingService, NewMapsStoreEveryParameterThatShapesThem) {
  store::TempDir dir;
  Config config = testing::configIn(dir.path());
  config.maps.occupancy.hit_log_odds = 0.5f;
  config.maps.occupancy.max_range_m = 12.0;
  config.maps.fusion.tolerance_log_odds = 0.0f;
  MappingService service(config);
  service.openMap("lab", 0.0);
  const std::vector<store::MapRecord> maps = service.store().maps();
  ASSERT_EQ(maps.size(), 1u);
  const nlohmann::json params = nlohmann::json::parse(maps[0].params_json);
  EXPECT_EQ(params.at("hit_log_odds").get<float>(), 0.5f);
  EXPECT_EQ(params.at("miss_log_odds").get<float>(), config.maps.occupancy.miss_log_odds);
  EXPECT_EQ(params.at("clamp_max_log_odds").get<float>(), config.maps.occupancy.clamp_max_log_odds);
  EXPECT_EQ(params.at("max_range_m").get<double>(), 12.0);
  EXPECT_EQ(params.at("fusion_tolerance_log_odds").get<float>(), 0.0f);
  EXPECT_EQ(params.at("free_space_tracing"), "stop_at_freed");
  EXPECT_EQ(params.at("sensor_model"), "beam");
}

TEST(MappingService, RecoveryRebuildsAMapWithItsStoredParametersNotTheConfigs) {
  store::TempDir dir;
  {
    Config creation = testing::configIn(dir.path());
    creation.maps.occupancy.hit_log_odds = 0.5f;
    creation.maps.occupancy.miss_log_odds = -0.25f;
    creation.maps.fusion.fuse_after_scans = 0;
    MappingService service(creation);
    service.openMap("lab", 0.2);
    logMessage(service.store(), testing::smallCloud(1));
  }  // no snapshot: the map was never applied anything in this process

  const Config now = testing::configIn(dir.path());  // defaults: hit 0.85, miss -0.41
  const MappingService service(now);
  const std::shared_ptr<MapWorker> map = service.findMap("lab");
  ASSERT_TRUE(map);
  EXPECT_EQ(map->map().resolution(), 0.2);
  EXPECT_EQ(map->map().occupancyParams().hit_log_odds, 0.5f);
  EXPECT_EQ(map->map().occupancyParams().miss_log_odds, -0.25f);
  EXPECT_EQ(map->map().fusionParams().fuse_after_scans, 0);
  // The logged cloud was replayed with them: its end cell (1.05 m at 0.2 m) holds exactly one hit.
  EXPECT_EQ(map->map().queryCell({5, 0, 0}).log_odds, 0.5f);
  EXPECT_EQ(map->map().queryCell({2, 0, 0}).log_odds, -0.25f);
}

TEST(MappingService, MapsStoredWithoutSomeParametersTakeTheConfigsForThose) {
  store::TempDir dir;
  {
    const std::unique_ptr<store::Store> store = store::Store::open(dir.path());
    // What older versions stored.
    store->ensureMap({"lab", 0.1, R"({"fusion_tolerance_log_odds":0.0,"max_range_m":0.5})", 1});
    logMessage(*store, testing::smallCloud(1));
  }
  Config config = testing::configIn(dir.path());
  config.maps.occupancy.hit_log_odds = 1.0f;
  const MappingService service(config);
  const map3d::CuboidMap& map = service.findMap("lab")->map();
  EXPECT_EQ(map.occupancyParams().max_range_m, 0.5);
  EXPECT_EQ(map.fusionParams().tolerance_log_odds, 0.0f);
  EXPECT_EQ(map.occupancyParams().hit_log_odds, 1.0f);
}

TEST(MappingService, UnreadableStoredParametersStopTheStartNamingTheMap) {
  store::TempDir dir;
  {
    const std::unique_ptr<store::Store> store = store::Store::open(dir.path());
    store->ensureMap({"lab", 0.1, "{not json", 1});
  }
  try {
    const MappingService service(testing::configIn(dir.path()));
    ADD_FAILURE() << "started";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("lab"), std::string::npos) << e.what();
  }
}

TEST(MappingService, WhenAppliedWaitsForTheMessageToBeInItsMap) {
  store::TempDir dir;
  MappingService service(testing::configIn(dir.path()));
  const std::shared_ptr<MapWorker> map = service.openMap("lab", 0.0);
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  map->post(0, std::make_shared<v1::RobotMessage>(), "test", [released] { released.wait(); });
  service.apply(*map, 7, std::make_shared<v1::RobotMessage>(testing::smallCloud(1)), "bot", nullptr);
  std::promise<bool> waited;
  std::future<bool> waited_result = waited.get_future();
  service.whenApplied(7, [&] { waited.set_value(map->appliedId() == 7); });
  EXPECT_EQ(waited_result.wait_for(std::chrono::milliseconds(100)), std::future_status::timeout);
  // Not being applied (e.g. recovered at start): at once.
  bool at_once = false;
  service.whenApplied(3, [&] { at_once = true; });
  EXPECT_TRUE(at_once);

  release.set_value();
  EXPECT_TRUE(waited_result.get());
}

TEST(MappingService, StopsItsWorkersEvenWhenSessionsStillHoldThem) {
  store::TempDir dir;
  std::shared_ptr<MapWorker> held;  // as a robot session with messages in flight would
  {
    MappingService service(testing::configIn(dir.path()));
    held = service.openMap("lab", 0.0);
    service.apply(*held, 1, std::make_shared<v1::RobotMessage>(testing::smallCloud(1)), "bot", nullptr);
  }
  // The final snapshot was written while the store was open, not when the last holder lets go.
  const std::unique_ptr<store::Store> store = store::Store::open(dir.path());
  const std::optional<store::Snapshot> snapshot = store->snapshot("lab");
  ASSERT_TRUE(snapshot);
  EXPECT_EQ(snapshot->last_message_id, 1);
  held.reset();
}

/// A MONO8 camera image of one grey, with a camera pose at (x, 0, 0).
v1::RobotMessage greyImage(uint64_t seq, uint8_t grey, double x) {
  v1::RobotMessage m;
  m.set_seq(seq);
  v1::CameraImage& image = *m.mutable_image();
  image.set_stamp_ns(static_cast<int64_t>(seq) * 1000);
  image.set_encoding(v1::CameraImage::MONO8);
  image.set_width(32);
  image.set_height(32);
  image.set_data(std::string(32 * 32, static_cast<char>(grey)));
  image.mutable_camera_pose()->mutable_position_m()->set_x(x);
  return m;
}

TEST(MappingService, CameraLoopClosuresAreStoredOnceAcrossReplaysOfTheLog) {
  store::TempDir dir;
  const RecognizerFactory recognizers = [](FrameKind kind) -> std::unique_ptr<PlaceRecognizer> {
    if (kind != FrameKind::kCamera) return nullptr;
    return std::make_unique<testing::SameGreyRecognizer>();
  };
  {
    MappingService service(testing::configIn(dir.path()), recognizers);
    const std::shared_ptr<MapWorker> map = service.openMap("lab", 0.0);
    const uint8_t greys[] = {10, 20, 30, 10};  // the fourth image is the first place again
    for (uint64_t seq = 1; seq <= 4; ++seq) {
      const v1::RobotMessage image = greyImage(seq, greys[seq - 1], static_cast<double>(seq));
      logMessage(service.store(), image);
      service.apply(*map, static_cast<int64_t>(seq), std::make_shared<v1::RobotMessage>(image), "bot", nullptr);
    }
    std::promise<void> applied;
    service.whenApplied(4, [&] { applied.set_value(); });
    applied.get_future().wait();
    map->drainLoopClosures();
    EXPECT_EQ(service.metrics().loop_closures[static_cast<size_t>(LoopSource::kCamera)].load(), 1u);
    EXPECT_EQ(service.metrics().loop_frames.load(), 4u);
  }
  const auto stored = [&](store::Store& store) { return store.loopClosures({"lab", "", "camera", 0, 100}); };
  {
    // Restarted: the images are replayed from the first one (below the snapshot too) and find the
    // same closure, which is not stored again.
    MappingService service(testing::configIn(dir.path()), recognizers);
    service.findMap("lab")->drainLoopClosures();
    EXPECT_EQ(service.metrics().loop_frames.load(), 4u);
    EXPECT_EQ(service.metrics().loop_closures[static_cast<size_t>(LoopSource::kCamera)].load(), 0u);
    const std::vector<store::LoopClosureRecord> closures = stored(service.store());
    ASSERT_EQ(closures.size(), 1u);
    EXPECT_EQ(closures[0].query_robot, "bot");
    EXPECT_EQ(closures[0].query_stamp_ns, 4000);
    EXPECT_EQ(closures[0].match_stamp_ns, 1000);
    const nlohmann::json json = loopClosureJson(closures[0]);
    EXPECT_EQ(json.at("query").at("position"), nlohmann::json::parse("[4.0, 0.0, 0.0]"));
    EXPECT_EQ(json.at("match").at("position"), nlohmann::json::parse("[1.0, 0.0, 0.0]"));
  }
  {
    // Without place recognition nothing below the snapshot is replayed for it.
    MappingService service(testing::configIn(dir.path()), RecognizerFactory{});
    EXPECT_EQ(service.metrics().messages_recovered.load(), 0u);
    EXPECT_EQ(stored(service.store()).size(), 1u);
  }
}

// The 2D pose graph can drop a closure it reported once later closures show it
// wrong: the stored one is marked withdrawn, once, and its viewers are told.
TEST(MappingService, AWithdrawnGeometryClosureIsMarkedInTheStoreAndPushedOnce) {
  store::TempDir dir;
  MappingService service(testing::configIn(dir.path()));
  service.openMap("lab", 0.0);
  auto viewer = std::make_shared<ViewerSession>(service.viewers(), "lab");
  auto connection = std::make_shared<testing::ViewerConnection>();
  viewer->onOpen(connection);
  connection->frames.clear();  // hello

  LoopClosure closure{"lab", LoopSource::kGeometry, {"bot", 2000, Eigen::Isometry3d::Identity()},
                      {"bot", 1000, Eigen::Isometry3d::Identity()}, 0.7, Eigen::Isometry3d::Identity()};
  service.recordLoopClosure(closure);
  closure.withdrawn = true;
  service.recordLoopClosure(closure);
  service.recordLoopClosure(closure);  // a replay of the log withdraws it again: nothing changes

  const std::vector<store::LoopClosureRecord> stored = service.store().loopClosures({"lab", "", "", 0, 100});
  ASSERT_EQ(stored.size(), 1u);
  ASSERT_TRUE(stored[0].withdrawn_ns);
  EXPECT_GE(*stored[0].withdrawn_ns, stored[0].detected_ns);
  EXPECT_EQ(service.metrics().loop_closures[static_cast<size_t>(LoopSource::kGeometry)].load(), 1u);
  EXPECT_EQ(service.metrics().loop_closures_withdrawn.load(), 1u);
  ASSERT_EQ(connection->frames.size(), 2u);
  EXPECT_EQ(connection->frames[0]["type"], "loop_closure");
  EXPECT_TRUE(connection->frames[0]["withdrawn_ns"].is_null());
  const nlohmann::json& withdrawn = connection->frames[1];
  EXPECT_EQ(withdrawn["type"], "loop_closure_withdrawn");
  EXPECT_EQ(withdrawn["id"], connection->frames[0]["id"]);
  EXPECT_EQ(withdrawn["withdrawn_ns"], *stored[0].withdrawn_ns);
  EXPECT_EQ(withdrawn["query"]["stamp_ns"], 2000);

  // A closure never stored is not withdrawn.
  LoopClosure other = closure;
  other.query.stamp_ns = 3000;
  service.recordLoopClosure(other);
  EXPECT_EQ(service.metrics().loop_closures_withdrawn.load(), 1u);
  EXPECT_EQ(connection->frames.size(), 2u);
  viewer->onClose();
}

TEST(MappingService, GaugesReadTheConnectionCounter) {
  store::TempDir dir;
  MappingService service(testing::configIn(dir.path()));
  EXPECT_EQ(service.gauges().http_connections, 0u);
  size_t open = 3;
  service.setConnectionCounter([&open] { return open; });
  EXPECT_EQ(service.gauges().http_connections, 3u);
  open = 5;
  EXPECT_EQ(service.gauges().http_connections, 5u);
}

}  // namespace
}  // namespace rmap::app
