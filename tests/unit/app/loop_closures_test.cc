#include "app/loop_closures.h"

#include <gtest/gtest.h>

namespace rmap::app {
namespace {

TEST(LoopClosures, TheJsonCarriesBothPlacesAndTheMeasuredRelativePoseWhenThereIsOne) {
  Eigen::Isometry3d at = Eigen::Isometry3d::Identity();
  at.translation() = Eigen::Vector3d(1.0, 2.0, 0.5);
  LoopClosure closure{"lab", LoopSource::kLaserIntensity, {"r2", 200, at}, {"r1", 100, std::nullopt}, 12.5,
                      std::nullopt};
  store::LoopClosureRecord record = toRecord(closure, 999);
  record.id = 7;
  EXPECT_EQ(record.source, "laser_intensity");
  EXPECT_EQ(record.query_robot, "r2");
  nlohmann::json json = loopClosureJson(record);
  EXPECT_EQ(json["id"], 7);
  EXPECT_EQ(json["score"], 12.5);
  EXPECT_EQ(json["detected_ns"], 999);
  EXPECT_EQ(json["query"]["position"], nlohmann::json::array({1.0, 2.0, 0.5}));
  EXPECT_TRUE(json["match"]["position"].is_null());
  EXPECT_TRUE(json["relative_pose"].is_null());

  Eigen::Isometry3d measured = Eigen::Isometry3d::Identity();
  measured.translation() = Eigen::Vector3d(0.3, -0.1, 0.0);
  measured.rotate(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()));
  closure.match_from_query = measured;
  json = loopClosureJson(toRecord(closure, 999));
  ASSERT_TRUE(json["relative_pose"].is_object());
  EXPECT_EQ(json["relative_pose"]["position"], nlohmann::json::array({0.3, -0.1, 0.0}));
  const nlohmann::json& q = json["relative_pose"]["orientation"];  // [w, x, y, z]
  EXPECT_NEAR(q[0].get<double>(), std::cos(0.1), 1e-12);
  EXPECT_NEAR(q[3].get<double>(), std::sin(0.1), 1e-12);
  EXPECT_TRUE(json["ambiguous_direction"].is_null());

  closure.ambiguous_direction = Eigen::Vector3d(0.6, -0.8, 0.0);
  json = loopClosureJson(toRecord(closure, 999));
  EXPECT_EQ(json["ambiguous_direction"], nlohmann::json::array({0.6, -0.8, 0.0}));
}

TEST(LoopClosures, SourcesParseByTheirApiNames) {
  for (LoopSource s : {LoopSource::kCamera, LoopSource::kLaserIntensity, LoopSource::kGeometry}) {
    EXPECT_EQ(parseLoopSource(toString(s)), s);
  }
  EXPECT_FALSE(parseLoopSource("lidar"));
}

}  // namespace
}  // namespace rmap::app
