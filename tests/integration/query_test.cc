// `rmap query` against a real rmapd fed with simulated lidar clouds: point, box (across
// pages) and batch answers equal the HTTP API's, in text and JSON; bad input exits non-zero.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "api_helpers.h"
#include "rmap_cli.h"
#include "rmapd_process.h"
#include "scene_clouds.h"

namespace rmap::testing {
namespace {

class Query : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir("rmap-query");
    rmapd_ = new RmapdProcess(dir_->path() / "data");
    streamAll(rmapd_->wsUrl(), "lidar", "lab", sceneClouds(client::makeSimScene(6), 3, 8));
    client::HttpClient http(rmapd_->httpUrl());
    waitForIdleFusion(http, "lab");
  }
  static void TearDownTestSuite() {
    delete rmapd_;
    delete dir_;
  }

  CliRun query(const std::string& args) const {
    return runRmap("query --server " + rmapd_->httpUrl() + " --map lab " + args, scratch_.path());
  }

  static TempDir* dir_;
  static RmapdProcess* rmapd_;
  TempDir scratch_{"rmap-query-out"};
  client::HttpClient http_{rmapd_->httpUrl(), {}, kWholeMapRequestTimeout};
};

TempDir* Query::dir_ = nullptr;
RmapdProcess* Query::rmapd_ = nullptr;

TEST_F(Query, PointAnswersAsTheApi) {
  const std::vector<nlohmann::json> cuboids = allCuboids(http_, "lab");
  ASSERT_FALSE(cuboids.empty());
  const nlohmann::json& c = cuboids[cuboids.size() / 2];
  // A point inside the cuboid's lowest cell.
  std::string xyz[3];
  for (int a = 0; a < 3; ++a) {
    std::ostringstream v;
    v.precision(17);
    v << c["min"][a].get<double>() + 0.01;
    xyz[a] = v.str();
  }
  const std::string point = xyz[0] + "," + xyz[1] + "," + xyz[2];
  const nlohmann::json expected = getJson(http_, "/v1/maps/lab/occupancy?x=" + xyz[0] + "&y=" + xyz[1] + "&z=" + xyz[2]);
  CliRun run = query("--point " + point + " --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json answer = nlohmann::json::parse(run.out);
  EXPECT_EQ(answer, expected);
  EXPECT_EQ(answer["state"], c["state"]);
  EXPECT_EQ(answer["cuboid"]["min"], c["min"]);
  run = query("--point " + point);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.out.rfind(c["state"].get<std::string>() + " ", 0), 0u) << run.out;
  EXPECT_NE(run.out.find(" cuboid "), std::string::npos) << run.out;
  // Far outside the map: unknown, no cuboid.
  run = query("--point 500,500,500");
  EXPECT_EQ(run.out, "unknown 0.5\n");
}

TEST_F(Query, BoxFollowsPagesToTheSameCuboidsAsOneRequest) {
  const nlohmann::json one = getJson(http_, "/v1/maps/lab/occupancy/box?min=-2,-2,0&max=2,2,2&limit=100000");
  ASSERT_GT(one["cuboids"].size(), 20u);
  ASSERT_TRUE(one["next_page_token"].is_null());
  const CliRun run = query("--box -2,-2,0,2,2,2 --page-size 7 --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(nlohmann::json::parse(run.out)["cuboids"], one["cuboids"]);
  const CliRun text = query("--box -2,-2,0,2,2,2");
  EXPECT_EQ(static_cast<size_t>(std::count(text.out.begin(), text.out.end(), '\n')), one["cuboids"].size());
}

TEST_F(Query, BatchFileAnswersAsTheBatchEndpoint) {
  const std::vector<Eigen::Vector3d> points{{0.05, 0.05, 0.05}, {1.0, 2.0, 1.3}, {-3.0, 1.0, 0.2}, {500, 0, 0}};
  const std::filesystem::path file = scratch_.path() / "points.txt";
  {
    std::ofstream out(file);
    out << "# x y z\n0.05 0.05 0.05\n1,2,1.3\n\n-3 1 0.2\n500 0 0\n";
  }
  const v1::OccupancyBatchResponse expected = batchQuery(http_, "lab", points);
  const CliRun run = query("--batch '" + file.string() + "' --json");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json answer = nlohmann::json::parse(run.out);
  ASSERT_EQ(answer["states"].size(), points.size());
  const char* names[] = {"unknown", "free", "occupied"};
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(answer["states"][i], names[expected.states(static_cast<int>(i))]) << i;
    EXPECT_FLOAT_EQ(answer["probabilities"][i].get<float>(), expected.probabilities(static_cast<int>(i)));
  }
  const CliRun text = query("--batch '" + file.string() + "'");
  EXPECT_EQ(std::count(text.out.begin(), text.out.end(), '\n'), 4);
  EXPECT_NE(text.out.find("500,0,0 unknown 0.5\n"), std::string::npos) << text.out;
}

TEST_F(Query, BadInputExitsWithAMessage) {
  CliRun run = query("--point 1,2");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("--point must be 3 finite numbers"), std::string::npos) << run.err;
  run = query("--point 1,2,3 --box 0,0,0,1,1,1");
  EXPECT_EQ(run.exit_code, 2) << run.err;
  run = query("--box 1,1,1,0,0,0");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("invalid_argument"), std::string::npos) << run.err;
  const std::filesystem::path file = scratch_.path() / "bad.txt";
  std::ofstream(file) << "1 2 3\n4 5\n";
  run = query("--batch '" + file.string() + "'");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("bad.txt:2:"), std::string::npos) << run.err;
  run = runRmap("query --server " + rmapd_->httpUrl() + " --map 'a/b' --point 0,0,0", scratch_.path());
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("map names are"), std::string::npos) << run.err;
  run = runRmap("query --server " + rmapd_->httpUrl() + " --map nope --point 0,0,0", scratch_.path());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("map_not_found"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace rmap::testing
