#include "app/viewer_hub.h"

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "service_test_support.h"

namespace rmap::app {
namespace {

using nlohmann::json;

/// A store that keeps nothing: enough for a MapWorker that is never started.
class NullStore : public store::Store {
 public:
  std::vector<store::AppendResult> append(std::span<const store::MessageRecord> m) override {
    return std::vector<store::AppendResult>(m.size());
  }
  void forEachMessage(const std::string&, int64_t, const std::function<bool(const store::StoredMessage&)>&) const override {}
  uint64_t messageCount() const override { return 0; }
  uint64_t lastSeq(const std::string&) const override { return 0; }
  store::MapRecord ensureMap(const store::MapRecord& map) override { return map; }
  std::vector<store::MapRecord> maps() const override { return {}; }
  void upsertRobot(const store::RobotRecord&) override {}
  std::vector<store::RobotRecord> robots() const override { return {}; }
  std::optional<store::RobotRecord> robot(const std::string&) const override { return std::nullopt; }
  void appendTrajectory(const std::string&, std::span<const store::TrajectoryPose>) override {}
  std::vector<store::TrajectoryPose> trajectory(const std::string&, int64_t, size_t) const override { return {}; }
  int64_t appendEvent(const store::EventRecord&) override { return 1; }
  std::vector<store::EventRecord> events(const std::string&, int64_t, size_t) const override { return {}; }
  std::optional<int64_t> appendLoopClosure(const store::LoopClosureRecord&) override { return 1; }
  std::optional<store::LoopClosureRecord> withdrawLoopClosure(const store::LoopClosureRecord&, int64_t) override {
    return std::nullopt;
  }
  std::vector<store::LoopClosureRecord> loopClosures(const store::LoopClosureFilter&) const override { return {}; }
  void putSnapshot(const store::Snapshot&) override {}
  std::optional<store::Snapshot> snapshot(const std::string&) const override { return std::nullopt; }
};

struct Viewer {
  std::shared_ptr<ViewerSession> session;
  std::shared_ptr<testing::ViewerConnection> connection;
};

class ViewerHubTest : public ::testing::Test {
 protected:
  static constexpr size_t kQueueBound = 1000;

  /// Opens a viewer of `map` and drops its hello frame.
  Viewer open(const std::string& map) {
    Viewer v{std::make_shared<ViewerSession>(hub_, map), std::make_shared<testing::ViewerConnection>()};
    v.session->onOpen(v.connection);
    EXPECT_EQ(v.connection->frames.size(), 1u);
    v.connection->frames.clear();
    return v;
  }

  static RobotPose pose(const std::string& robot, const std::string& map, uint64_t seq, double x) {
    RobotPose p{robot, map, seq, int64_t(seq) * 1000, Eigen::Isometry3d::Identity()};
    p.pose.translation() = Eigen::Vector3d(x, 2.0, 3.0);
    return p;
  }

  Metrics metrics_;
  ViewerHub hub_{metrics_, kQueueBound};
};

TEST_F(ViewerHubTest, OpenSendsHelloAndRegistersCloseUnregisters) {
  auto session = std::make_shared<ViewerSession>(hub_, "lab");
  auto connection = std::make_shared<testing::ViewerConnection>();
  session->onOpen(connection);
  ASSERT_EQ(connection->frames.size(), 1u);
  EXPECT_EQ(connection->frames[0], (json{{"type", "hello"}, {"map", "lab"}}));
  EXPECT_EQ(hub_.viewers(), 1u);
  session->onClose();
  EXPECT_EQ(hub_.viewers(), 0u);
  hub_.publishEvent("lab", {{"type", "loop_closure"}});
  EXPECT_EQ(connection->frames.size(), 1u);
}

TEST_F(ViewerHubTest, TickSendsPosesToViewersOfTheMapAndOfAllMaps) {
  const Viewer lab = open("lab"), other = open("other"), all = open("");
  hub_.publishPose(pose("r1", "lab", 7, 1.5));
  hub_.tick({});

  ASSERT_EQ(lab.connection->frames.size(), 1u);
  const json& frame = lab.connection->frames[0];
  EXPECT_EQ(frame["type"], "poses");
  EXPECT_EQ(frame["map"], "lab");
  ASSERT_EQ(frame["poses"].size(), 1u);
  EXPECT_EQ(frame["poses"][0]["robot_id"], "r1");
  EXPECT_EQ(frame["poses"][0]["seq"], 7);
  EXPECT_EQ(frame["poses"][0]["position"], (json{1.5, 2.0, 3.0}));
  EXPECT_EQ(frame["poses"][0]["orientation"], (json{1.0, 0.0, 0.0, 0.0}));
  EXPECT_TRUE(other.connection->frames.empty());
  ASSERT_EQ(all.connection->frames.size(), 1u);
  EXPECT_EQ(all.connection->frames[0], frame);
  EXPECT_EQ(metrics_.viewer_frames_sent.load(), 2u);
}

TEST_F(ViewerHubTest, TickSendsOnlyTheLatestPoseOfEachRobotOnce) {
  const Viewer lab = open("lab");
  hub_.publishPose(pose("r1", "lab", 1, 1.0));
  hub_.publishPose(pose("r1", "lab", 2, 2.0));
  hub_.publishPose(pose("r2", "lab", 5, 3.0));
  hub_.tick({});
  hub_.tick({});
  ASSERT_EQ(lab.connection->frames.size(), 1u);
  const json& poses = lab.connection->frames[0]["poses"];
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[0]["robot_id"], "r1");
  EXPECT_EQ(poses[0]["seq"], 2);
  EXPECT_EQ(poses[1]["robot_id"], "r2");
}

TEST_F(ViewerHubTest, EventsGoToViewersOfTheirMap) {
  const Viewer lab = open("lab"), other = open("other");
  hub_.publishEvent("lab", {{"type", "loop_closure"}, {"id", 3}});
  ASSERT_EQ(lab.connection->frames.size(), 1u);
  EXPECT_EQ(lab.connection->frames[0]["id"], 3);
  EXPECT_TRUE(other.connection->frames.empty());
}

TEST_F(ViewerHubTest, ViewerBehindMissesFramesThenGetsResyncFirst) {
  const Viewer slow = open("lab"), fast = open("lab");
  slow.connection->queued = kQueueBound;
  hub_.publishEvent("lab", {{"n", 1}});
  EXPECT_TRUE(slow.connection->frames.empty());
  EXPECT_EQ(metrics_.viewer_frames_dropped.load(), 1u);
  EXPECT_EQ(fast.connection->frames.size(), 1u);

  slow.connection->queued = kQueueBound / 2 + 1;  // draining, not yet below half the bound
  hub_.publishEvent("lab", {{"n", 2}});
  EXPECT_TRUE(slow.connection->frames.empty());
  EXPECT_EQ(metrics_.viewer_frames_dropped.load(), 2u);

  slow.connection->queued = 0;
  hub_.publishEvent("lab", {{"n", 3}});
  ASSERT_EQ(slow.connection->frames.size(), 2u);
  EXPECT_EQ(slow.connection->frames[0], (json{{"type", "resync"}}));
  EXPECT_EQ(slow.connection->frames[1], (json{{"n", 3}}));
  hub_.publishEvent("lab", {{"n", 4}});
  ASSERT_EQ(slow.connection->frames.size(), 3u);
  EXPECT_EQ(slow.connection->frames[2], (json{{"n", 4}}));
  EXPECT_EQ(metrics_.viewer_frames_dropped.load(), 2u);
  EXPECT_EQ(fast.connection->frames.size(), 4u);
}

TEST_F(ViewerHubTest, BacklogCountsTheSkippedViewersAndTheQueuedBytes) {
  const Viewer slow = open("lab"), fast = open("lab");
  EXPECT_EQ(hub_.backlog().skipping, 0u);
  slow.connection->queued = kQueueBound;
  fast.connection->queued = 10;
  hub_.publishEvent("lab", {{"n", 1}});
  EXPECT_EQ(hub_.backlog().skipping, 1u);
  EXPECT_EQ(hub_.backlog().queued_bytes, kQueueBound + 10);
  slow.connection->queued = 0;
  hub_.publishEvent("lab", {{"n", 2}});
  EXPECT_EQ(hub_.backlog().skipping, 0u) << "caught up and resynchronised";
}

TEST_F(ViewerHubTest, FrameThatWouldOverflowTheQueueIsDropped) {
  const Viewer viewer = open("lab");
  viewer.connection->queued = kQueueBound - 10;
  hub_.publishEvent("lab", {{"padding", std::string(20, 'x')}});
  EXPECT_TRUE(viewer.connection->frames.empty());
  EXPECT_EQ(metrics_.viewer_frames_dropped.load(), 1u);
}

TEST_F(ViewerHubTest, RefusedSendAlsoOwesAResync) {
  const Viewer viewer = open("lab");
  viewer.connection->accept = false;
  hub_.publishEvent("lab", {{"n", 1}});
  EXPECT_EQ(metrics_.viewer_frames_dropped.load(), 1u);
  viewer.connection->accept = true;
  hub_.publishEvent("lab", {{"n", 2}});
  ASSERT_EQ(viewer.connection->frames.size(), 2u);
  EXPECT_EQ(viewer.connection->frames[0]["type"], "resync");
  EXPECT_EQ(viewer.connection->frames[1]["n"], 2);
}

TEST_F(ViewerHubTest, TickSendsTileChangesOfAMapWorkerOnce) {
  const Viewer lab = open("lab"), other = open("other");
  const Config config;
  NullStore store;
  const RobotSensors sensors;
  const Calibrations calibrations;
  const RecognizerFactory no_recognition;
  auto worker = std::make_shared<MapWorker>("lab", std::make_unique<map3d::CuboidMap>(0.1), 0, config, store,
                                            metrics_, [&](const RobotPose& p) { hub_.publishPose(p); },
                                            MapWorker::Slam2dInputs{calibrations, sensors, nullptr, 0},
                                            MapWorker::LoopInputs{no_recognition, nullptr, 0});
  v1::RobotMessage cloud;
  cloud.set_seq(1);
  cloud.mutable_cloud()->set_frame(v1::PointCloud::MAP);
  cloud.mutable_cloud()->mutable_sensor_pose()->mutable_position_m()->set_x(0.05);
  for (const float v : {2.0f, 0.05f, 0.05f, 2.0f, -0.5f, -0.5f}) cloud.mutable_cloud()->add_xyz_m(v);
  worker->applyNow(1, cloud, "r1");

  hub_.tick({worker});
  ASSERT_EQ(lab.connection->frames.size(), 2u);
  const json& tiles = lab.connection->frames[0];
  EXPECT_EQ(tiles["type"], "tiles");
  EXPECT_EQ(tiles["map"], "lab");
  EXPECT_EQ(tiles["map_version"], worker->map().version());
  const std::vector<TileVersion> known = worker->tiles().tiles(0);
  ASSERT_FALSE(known.empty());
  size_t level0 = 0;
  for (const json& t : tiles["tiles"]) {
    ASSERT_EQ(t.size(), 5u);
    EXPECT_EQ(t[4], worker->map().version());
    if (t[0] == 0) ++level0;
  }
  EXPECT_EQ(level0, known.size());
  EXPECT_EQ(lab.connection->frames[1]["type"], "poses");
  EXPECT_EQ(lab.connection->frames[1]["poses"][0]["robot_id"], "r1");
  EXPECT_TRUE(other.connection->frames.empty());

  hub_.tick({worker});
  EXPECT_EQ(lab.connection->frames.size(), 2u);
}

}  // namespace
}  // namespace rmap::app
