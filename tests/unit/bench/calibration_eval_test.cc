#include "slam2d/calibration_eval.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

namespace rmap::bench {
namespace {

TEST(CalibrationEval, BothSimulatedScannersMeetTheTargetsOnAShortTour) {
  CalibrationEvalOptions o;
  o.poses = 40;
  const std::vector<ScannerCalibrationEval> results = evaluateSimulatedCalibration(o);
  ASSERT_EQ(results.size(), 2u);
  EXPECT_EQ(results[0].scanner, "sick_like");
  EXPECT_EQ(results[1].scanner, "hokuyo_like");
  for (const ScannerCalibrationEval& e : results) {
    SCOPED_TRACE(e.scanner);
    EXPECT_EQ(e.scans, 40u);
    EXPECT_GT(e.returns, 10000u);
    EXPECT_GT(e.spread_cells, 100u);
    EXPECT_LT(e.incidence_err_deg_median, 1.5);
    for (const CalibrationScore* s : {&e.supervised, &e.self}) {
      EXPECT_LT(s->rel_err_median, 0.05);
      EXPECT_GT(s->coverage, 0.75);
      EXPECT_GT(e.spread_raw, 5.0 * s->spread);
    }
    EXPECT_NE(e.supervised_calibration.find("rmap_intensity_calibration 1"), std::string::npos);
  }
  EXPECT_NEAR(results[0].saturation_detected, results[0].saturation_true * 0.94, 0.03 * results[0].saturation_true);
  const nlohmann::json j = toJson(results[1]);
  EXPECT_EQ(j.at("scanner"), "hokuyo_like");
  EXPECT_TRUE(j.at("self").contains("reflectivity_rel_err_median"));
}

TEST(CalibrationEval, RealLidarPairIsRead) {
  const std::string dir = std::string(RMAP_SHARED_DATA_DIR) + "/lidar-intensity/small-gicp-pair";
  if (!std::filesystem::exists(dir + "/source.ply")) GTEST_SKIP() << "shared data not found: " << dir;
  const LidarIntensityCheck c = evaluateLidarPair(dir, CalibrationEvalOptions{});
  EXPECT_GT(c.points[0], 60000u);
  EXPECT_GT(c.planar_points[1], 20000u);
  EXPECT_GT(c.shared_cells, 100u);
  EXPECT_GT(c.spearman_cos, 0.2);  // brighter towards normal incidence
  EXPECT_LT(c.between_scans_calibrated, c.between_scans_raw);
}

}  // namespace
}  // namespace rmap::bench
