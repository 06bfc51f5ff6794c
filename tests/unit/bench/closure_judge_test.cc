#include "slam2d/closure_judge.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace rmap::bench {
namespace {

using slam2d::Pose2;

constexpr double kDeg = std::numbers::pi / 180.0;

/// Ten scans 1 m apart along x, turning 10° each; the laser 0.2 m ahead of
/// the robot's centre; the estimate equals the truth.
struct TenScanRun {
  JudgedRun judged;
  std::vector<Pose2> robot_truth;
  TenScanRun() {
    const Pose2 mount{0.2, 0.0, 0.0};
    for (int i = 0; i < 10; ++i) {
      robot_truth.push_back({double(i), 0.5 * i, 10.0 * kDeg * i});
      judged.stamps_ns.push_back(1000 + i);
      judged.sensor_mounts.push_back(mount);
      judged.laser_poses.push_back(robot_truth.back() * mount);
    }
  }
  /// A closure whose relative robot pose is the truth's, then `error` on top.
  slam2d::LoopClosure2d closure(size_t query, size_t match, const Pose2& error = {}) const {
    slam2d::LoopClosure2d c;
    c.query_stamp_ns = judged.stamps_ns[query];
    c.match_stamp_ns = judged.stamps_ns[match];
    c.relative = between(robot_truth[match], robot_truth[query]) * error;
    return c;
  }
  /// The same closure, matched against the submap of scans [first, last] anchored at `match`.
  slam2d::LoopClosure2d closureOnSubmap(size_t query, size_t match, size_t first, size_t last,
                                        const Pose2& error = {}) const {
    slam2d::LoopClosure2d c = closure(query, match, error);
    for (size_t k = first; k <= last; ++k)
      c.match_submap.push_back({judged.stamps_ns[k], between(robot_truth[match], robot_truth[k])});
    return c;
  }
  ClosureJudge truthJudge(const std::string& name) const {
    return {name, std::vector<std::optional<Pose2>>(judged.laser_poses.begin(), judged.laser_poses.end()), {}};
  }
};

TEST(ClosureJudge, AClosureIsFalseBeyondThreeDecimetresOrFiveDegrees) {
  const TenScanRun run;
  const std::vector<slam2d::LoopClosure2d> closures = {
      run.closure(8, 2),                          // right, in laser and robot frames alike
      run.closure(9, 3, {0.25, 0.0, 4.0 * kDeg}),  // off, within the bounds
      run.closure(7, 1, {0.0, 0.35, 0.0}),         // 0.35 m off
      run.closure(6, 0, {0.0, 0.0, 6.0 * kDeg}),   // 6° off
  };
  const nlohmann::json r = judgeClosures(closures, {}, run.judged, {run.truthJudge("truth")});
  EXPECT_EQ(r["closures_judged"], 4);
  EXPECT_EQ(r["false_closures"], 2);
  EXPECT_EQ(r["judged_by"], "truth");
  EXPECT_TRUE(r["false_by_all_judges"].is_null());  // one judge only
  const nlohmann::json& list = r["list"];
  ASSERT_EQ(list.size(), 4u);
  EXPECT_NEAR(list[0]["error_m"].get<double>(), 0.0, 1e-9);
  EXPECT_FALSE(list[0]["false"].get<bool>());
  EXPECT_NEAR(list[1]["error_deg"].get<double>(), 4.0, 1e-6);
  EXPECT_FALSE(list[1]["false"].get<bool>());
  EXPECT_TRUE(list[2]["false"].get<bool>());
  EXPECT_NEAR(list[3]["error_deg"].get<double>(), 6.0, 1e-6);
  EXPECT_TRUE(list[3]["false"].get<bool>());
  EXPECT_FALSE(list[0].contains("by_judge"));
  EXPECT_NEAR(r["worst_closure_error_m"].get<double>(), list[2]["error_m"].get<double>(), 1e-12);
}

// An ambiguous closure (a corridor) measures its relative pose across its
// rival's direction only: it stays false by the full error, and is also judged
// across that direction alone.
TEST(ClosureJudge, AnAmbiguousClosureIsAlsoJudgedAcrossItsRival) {
  const TenScanRun run;
  std::vector<slam2d::LoopClosure2d> closures = {
      run.closure(8, 2, {0.4, 0.0, 0.0}),  // slid 0.4 m along its rival's direction
      run.closure(7, 1, {0.0, 0.4, 0.0}),  // 0.4 m off across it
      run.closure(6, 0, {0.4, 0.0, 0.0}),  // slid, and not ambiguous
  };
  // The rival's direction in the match's frame: the query's x axis (the error's frame) seen from the match.
  for (size_t i : {0, 1}) {
    const slam2d::LoopClosure2d& c = closures[i];
    closures[i].ambiguous_direction = Eigen::Rotation2Dd(c.relative.theta_rad) * Eigen::Vector2d::UnitX();
  }
  const nlohmann::json r = judgeClosures(closures, {}, run.judged, {run.truthJudge("truth")});
  EXPECT_EQ(r["false_closures"], 3);
  EXPECT_EQ(r["ambiguous_closures"], 2);
  EXPECT_EQ(r["false_across_ambiguity"], 2);
  const nlohmann::json& list = r["list"];
  EXPECT_TRUE(list[0]["ambiguous"].get<bool>());
  EXPECT_NEAR(list[0]["error_across_ambiguity_m"].get<double>(), 0.0, 1e-9);
  EXPECT_FALSE(list[0]["false_across_ambiguity"].get<bool>());
  EXPECT_NEAR(list[1]["error_across_ambiguity_m"].get<double>(), 0.4, 1e-9);
  EXPECT_TRUE(list[1]["false_across_ambiguity"].get<bool>());
  EXPECT_FALSE(list[2]["ambiguous"].get<bool>());
  EXPECT_FALSE(list[2].contains("error_across_ambiguity_m"));
}

/// `scans` scans 0.25 m apart, out along x and back 0.1 m aside (turned); the
/// estimate and the odometry are the truth; no scan points.
JudgedRun outAndBack(int scans) {
  JudgedRun run;
  for (int i = 0; i < scans; ++i) {
    const int back = scans - 1 - i;
    const Pose2 laser = 2 * i < scans ? Pose2{0.25 * i, 0.0, 0.0} : Pose2{0.25 * back, 0.1, std::numbers::pi};
    run.stamps_ns.push_back(1000 + i);
    run.sensor_mounts.push_back({});
    run.laser_poses.push_back(laser);
    run.laser_odometry.push_back(laser);
  }
  return run;
}

/// outAndBack(40) whose scans each see the same 300 scattered landmarks (drawn with `seed`).
JudgedRun outAndBackAmongLandmarks(unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> along(-3.0, 8.0), across(-4.0, 4.0);
  std::vector<Eigen::Vector2d> landmarks;
  for (int i = 0; i < 300; ++i) landmarks.emplace_back(along(random), across(random));
  JudgedRun run = outAndBack(40);
  for (const Pose2& laser : run.laser_poses) {
    std::vector<Eigen::Vector2d> seen;
    for (const Eigen::Vector2d& l : landmarks) seen.push_back(laser.inverse() * l);
    run.scan_points.push_back(std::move(seen));
  }
  return run;
}

/// A closure of `run` from `match` to `query` at the estimate's relative pose, then `error` on top.
slam2d::LoopClosure2d closureOf(const JudgedRun& run, size_t query, size_t match, const Pose2& error) {
  slam2d::LoopClosure2d c;
  c.query_stamp_ns = run.stamps_ns[query];
  c.match_stamp_ns = run.stamps_ns[match];
  c.relative = between(run.laser_poses[match], run.laser_poses[query]) * error;
  return c;
}

// A false verdict is checked against the scans: the query's scan fitted to
// the judge's local map of the match. Where the judge's own pose is off (a
// corrected log off along a corridor), the closure's pose fits better and the
// verdict is not confirmed; a closure truly off is.
TEST(ClosureJudge, TheScansShowWhetherAFalseVerdictIsTheJudgesError) {
  JudgedRun run = outAndBackAmongLandmarks(7);
  ClosureJudge judge{"off at scan 39", std::vector<std::optional<Pose2>>(run.laser_poses.begin(), run.laser_poses.end()), {}};
  judge.reference[39] = *judge.reference[39] * Pose2{0.4, 0.0, 0.0};
  const std::vector<slam2d::LoopClosure2d> closures = {closureOf(run, 39, 0, {}), closureOf(run, 38, 1, {0.4, 0.0, 0.0})};

  const nlohmann::json r = judgeClosures(closures, {}, run, {judge});
  EXPECT_EQ(r["false_closures"], 2);
  EXPECT_EQ(r["false_confirmed_by_scans"], 1);
  EXPECT_EQ(r["false_across_ambiguity_confirmed_by_scans"], 1);
  // The judge's 0.4 m at scan 39 is below a jump: both lie away from one, and the confirmed one is credible.
  EXPECT_EQ(r["false_away_from_judge_jumps"], 2);
  EXPECT_EQ(r["false_credible"], 1);
  const nlohmann::json& list = r["list"];
  ASSERT_EQ(list.size(), 2u);
  EXPECT_TRUE(list[0]["false"].get<bool>()) << "the judge's pose of scan 39 is 0.4 m off";
  EXPECT_FALSE(list[0]["confirmed_by_scans"].get<bool>());
  EXPECT_LT(list[0]["scan_fit_closure_m"].get<double>(), 1e-9);
  EXPECT_GT(list[0]["scan_fit_judge_m"].get<double>(), 0.1);
  EXPECT_TRUE(list[1]["false"].get<bool>());
  EXPECT_TRUE(list[1]["confirmed_by_scans"].get<bool>());
  EXPECT_LT(list[1]["scan_fit_judge_m"].get<double>(), 1e-9);
  EXPECT_GT(list[1]["scan_fit_closure_m"].get<double>(), 0.1);

  run.scan_points.clear();  // no scans: no check
  const nlohmann::json unchecked = judgeClosures(closures, {}, run, {judge});
  EXPECT_EQ(unchecked["false_closures"], 2);
  EXPECT_TRUE(unchecked["false_confirmed_by_scans"].is_null());
  EXPECT_TRUE(unchecked["false_credible"].is_null());
  EXPECT_FALSE(unchecked["list"][0].contains("confirmed_by_scans"));
}

TEST(ClosureJudge, FalseVerdictsNextToAJumpOfTheJudgeAreCountedApart) {
  // 60 scans out and back; the odometry is exact. The judge jumps 1 m sideways between scans 45 and 46 (a particle filter's
  // correction): its poses from 46 on are 1 m off the run's.
  JudgedRun run = outAndBack(60);
  ClosureJudge judge{"jumps at 46", std::vector<std::optional<Pose2>>(run.laser_poses.begin(), run.laser_poses.end()), {}};
  for (size_t k = 46; k < 60; ++k) judge.reference[k] = Pose2{0.0, 1.0, 0.0} * *judge.reference[k];
  EXPECT_NEAR(*judgeJump_m(judge, run, 46), 1.0, 1e-9);
  EXPECT_NEAR(*judgeJump_m(judge, run, 31), 1.0, 1e-9) << "step 45 → 46 lies within 15 scans";
  EXPECT_NEAR(*judgeJump_m(judge, run, 30), 0.0, 1e-9) << "step 45 → 46 lies beyond 15 scans";
  EXPECT_NEAR(*judgeJump_m(judge, run, 59), 1.0, 1e-9) << "the last scan's steps end with the run";

  // Right, but false by the judge's jump; and 0.4 m off, far from it.
  const std::vector<slam2d::LoopClosure2d> closures = {closureOf(run, 50, 10, {}), closureOf(run, 25, 5, {0.4, 0.0, 0.0})};
  const nlohmann::json r = judgeClosures(closures, {}, run, {judge});
  EXPECT_EQ(r["false_closures"], 2);
  EXPECT_EQ(r["false_away_from_judge_jumps"], 1);
  EXPECT_EQ(r["false_across_ambiguity_away_from_judge_jumps"], 1);
  EXPECT_EQ(r["judges"][0]["false_away_from_judge_jumps"], 1);
  EXPECT_TRUE(r["false_credible"].is_null()) << "no scans: not every check can be made";
  ASSERT_EQ(r["list"].size(), 2u);
  EXPECT_NEAR(r["list"][0]["judge_jump_m"].get<double>(), 1.0, 1e-9);
  EXPECT_NEAR(r["list"][1]["judge_jump_m"].get<double>(), 0.0, 1e-9);

  // Without odometry at a scan its steps are not compared; without any, no check.
  run.laser_odometry.assign(run.laser_odometry.size(), std::nullopt);
  EXPECT_FALSE(judgeJump_m(judge, run, 46).has_value());
  run.laser_odometry.clear();
  const nlohmann::json unchecked = judgeClosures(closures, {}, run, {judge});
  EXPECT_EQ(unchecked["false_closures"], 2);
  EXPECT_TRUE(unchecked["false_away_from_judge_jumps"].is_null());
  EXPECT_FALSE(unchecked["list"][0].contains("judge_jump_m"));
  EXPECT_TRUE(unchecked["false_credible"].is_null());
}

TEST(ClosureJudge, ScanFitIsTheMeanTruncatedDistanceToTheNearestMapPoint) {
  const std::vector<Eigen::Vector2d> map = {{0.0, 0.0}, {1.0, 0.0}};
  const std::vector<Eigen::Vector2d> points = {{0.0, 0.1}, {5.0, 5.0}};
  EXPECT_NEAR(scanFit_m(points, {}, map), (0.1 + kScanFitTruncation_m) / 2, 1e-12);
  EXPECT_NEAR(scanFit_m(points, {1.0, -0.1, 0.0}, map), (0.0 + kScanFitTruncation_m) / 2, 1e-12);
  EXPECT_EQ(scanFit_m({}, {}, map), kScanFitTruncation_m);
  slam2d::LaserScan scan;
  scan.range_min_m = 0.1f;
  scan.range_max_m = 10.0f;
  scan.angles_rad = {0.0f, float(std::numbers::pi / 2), 0.0f, 0.0f, 0.0f};
  scan.ranges_m = {2.0f, 1.0f, 10.0f, 0.05f, std::nanf("")};
  const std::vector<Eigen::Vector2d> returns = scanReturns(scan);
  ASSERT_EQ(returns.size(), 2u) << "the maximum, below the minimum and NaN are no returns";
  EXPECT_NEAR((returns[0] - Eigen::Vector2d(2.0, 0.0)).norm(), 0.0, 1e-6);
  EXPECT_NEAR((returns[1] - Eigen::Vector2d(0.0, 1.0)).norm(), 0.0, 1e-6);
}

// Two corrections of one run can disagree on a single scan: each judge's
// verdict is kept, and a closure counts as false by all only when every
// judge says so.
TEST(ClosureJudge, EachJudgeGivesItsVerdict) {
  const TenScanRun run;
  ClosureJudge skewed = run.truthJudge("skewed");
  *skewed.reference[2] = *skewed.reference[2] * Pose2{0.0, 0.0, 12.0 * kDeg};  // one pose of this correction is off
  const std::vector<slam2d::LoopClosure2d> closures = {
      run.closure(8, 2),                        // right: only the skewed judge calls it false
      run.closure(9, 4, {0.5, 0.0, 0.0}),       // wrong: both do
      run.closure(7, 3),                        // right: both agree
  };
  const nlohmann::json r = judgeClosures(closures, {}, run.judged, {run.truthJudge("truth"), skewed});
  EXPECT_EQ(r["false_closures"], 1);  // the first judge's
  ASSERT_EQ(r["judges"].size(), 2u);
  EXPECT_EQ(r["judges"][0]["false_closures"], 1);
  EXPECT_EQ(r["judges"][1]["false_closures"], 2);
  EXPECT_EQ(r["judges"][1]["judged_by"], "skewed");
  EXPECT_EQ(r["closures_judged_by_all"], 3);
  EXPECT_EQ(r["false_by_all_judges"], 1);
  const nlohmann::json& first = r["list"][0];
  EXPECT_FALSE(first["false"].get<bool>());
  EXPECT_FALSE(first["by_judge"][0]["false"].get<bool>());
  EXPECT_TRUE(first["by_judge"][1]["false"].get<bool>());
  EXPECT_NEAR(first["by_judge"][1]["error_deg"].get<double>(), 12.0, 1e-6);
}

// A closure the graph withdrew later was still accepted: it counts, flagged.
// The scan was matched against the submap, not the anchor's scan: a judge
// whose pose of the anchor alone is off still judges the closure right
// against the submap as a whole, and a closure that is off stays false.
TEST(ClosureJudge, AgainstTheWholeSubmapABadReferencePoseOfTheAnchorDoesNotMakeAClosureFalse) {
  const TenScanRun run;
  ClosureJudge skewed = run.truthJudge("skewed");
  *skewed.reference[2] = *skewed.reference[2] * Pose2{0.1, 0.0, 12.0 * kDeg};  // the anchor's pose is off
  const std::vector<slam2d::LoopClosure2d> closures = {
      run.closureOnSubmap(8, 2, 0, 4),                           // right
      run.closureOnSubmap(9, 2, 0, 4, {0.0, 0.4, 0.0}),          // 0.4 m off
      run.closureOnSubmap(7, 3, 3, 4),                           // too few keyframes with a pose: not judged so
  };
  const nlohmann::json r = judgeClosures(closures, {}, run.judged, {skewed});
  EXPECT_EQ(r["false_closures"], 2);  // against the anchor's pose the right one looks 12° off
  EXPECT_EQ(r["false_against_submap"], 1);
  EXPECT_EQ(r["judges"][0]["closures_judged_against_submap"], 2);
  const nlohmann::json& list = r["list"];
  EXPECT_TRUE(list[0]["false"].get<bool>());
  EXPECT_NEAR(list[0]["error_deg"].get<double>(), 12.0, 1e-6);
  EXPECT_FALSE(list[0]["false_against_submap"].get<bool>());
  // One skewed keyframe of five: the median heading ignores it, the mean position moves 2 cm.
  EXPECT_LT(list[0]["submap_error_deg"].get<double>(), 1e-6);
  EXPECT_LT(list[0]["submap_error_m"].get<double>(), 0.1);
  EXPECT_TRUE(list[1]["false_against_submap"].get<bool>());
  EXPECT_NEAR(list[1]["submap_error_m"].get<double>(), 0.4, 0.1);
  EXPECT_FALSE(list[2].contains("submap_error_m"));
}

TEST(ClosureJudge, WithdrawnClosuresStayCountedAndAreFlagged) {
  const TenScanRun run;
  const std::vector<slam2d::LoopClosure2d> closures = {run.closure(8, 2), run.closure(7, 1, {0.0, 0.35, 0.0}),
                                                       run.closure(6, 0, {0.0, 0.0, 6.0 * kDeg})};
  const nlohmann::json r = judgeClosures(closures, {closures[1]}, run.judged, {run.truthJudge("truth")});
  EXPECT_EQ(r["closures"], 3);
  EXPECT_EQ(r["withdrawn"], 1);
  // Where scans share stamps, the measurement tells closures apart.
  slam2d::LoopClosure2d same_stamps = closures[0];
  same_stamps.relative.x_m += 1e-3;
  EXPECT_EQ(judgeClosures(closures, {same_stamps}, run.judged, {})["withdrawn"], 0);
  EXPECT_EQ(r["false_closures"], 2);
  EXPECT_EQ(r["false_closures_withdrawn"], 1);
  EXPECT_EQ(r["judges"][0]["false_closures_withdrawn"], 1);
  EXPECT_FALSE(r["list"][0]["withdrawn"].get<bool>());
  EXPECT_TRUE(r["list"][1]["withdrawn"].get<bool>());
  EXPECT_FALSE(r["list"][2]["withdrawn"].get<bool>());
}

TEST(ClosureJudge, AScanWithoutAReferenceBorrowsItsNearestNeighboursThroughTheEstimate) {
  TenScanRun run;
  ClosureJudge sparse = run.truthJudge("sparse");
  for (size_t i : {1, 2, 3, 5, 6, 7, 8}) sparse.reference[i].reset();
  const slam2d::LoopClosure2d right = run.closure(8, 2);
  nlohmann::json r = judgeClosures({right}, {}, run.judged, {sparse});
  EXPECT_EQ(r["closures_judged"], 1);
  EXPECT_NEAR(r["list"][0]["error_m"].get<double>(), 0.0, 1e-9);
  // The estimate carries the borrowed pose: scan 2 borrows scan 0's, so an
  // estimate bent between the two shows in the verdict.
  run.judged.laser_poses[2] = run.judged.laser_poses[2] * Pose2{0.0, 0.0, 7.0 * kDeg};
  r = judgeClosures({right}, {}, run.judged, {sparse});
  EXPECT_NEAR(r["list"][0]["error_deg"].get<double>(), 7.0, 1e-6);
  // Beyond the borrowing distance nothing is judged.
  ClosureJudge none = run.truthJudge("none");
  for (auto& p : none.reference) p.reset();
  r = judgeClosures({right}, {}, run.judged, {none});
  EXPECT_EQ(r["closures_judged"], 0);
  EXPECT_TRUE(r["false_closures"].is_null());
  EXPECT_FALSE(r["list"][0].contains("error_m"));
}

// A corrected log can be off the checked relations at a scan: what it would
// judge there is not judged, rather than called false for the judge's error.
TEST(ClosureJudge, APoseTheRelationsContradictJudgesNothing) {
  const TenScanRun run;
  ClosureJudge bent = run.truthJudge("bent");
  *bent.reference[2] = *bent.reference[2] * Pose2{0.0, 0.0, 7.0 * kDeg};
  const auto relation = [&](size_t from, size_t to) {
    return datasets::SlamRelation{run.judged.stamps_ns[from], run.judged.stamps_ns[to],
                                  between(run.judged.laser_poses[from], run.judged.laser_poses[to]), 0};
  };
  const std::vector<slam2d::LoopClosure2d> closures = {run.closure(8, 2), run.closure(9, 5)};
  nlohmann::json r = judgeClosures(closures, {}, run.judged, {bent});
  EXPECT_EQ(r["false_closures"], 1) << "without relations the bent pose makes a right closure false";
  EXPECT_EQ(r["judge_poses_contradicted"], 0);

  // Relations 1→2 and 2→3 miss the bent pose by 7°; each condemns both its poses. 5→6 holds.
  r = judgeClosures(closures, {}, run.judged, {bent}, {relation(1, 2), relation(2, 3), relation(5, 6)});
  EXPECT_EQ(r["judge_poses_contradicted"], 3);
  EXPECT_EQ(r["judges"][0]["judge_poses_contradicted"], 3);
  EXPECT_EQ(r["closures_judged"], 1);
  EXPECT_EQ(r["false_closures"], 0);
  EXPECT_FALSE(r["list"][0].contains("error_m"));
  EXPECT_NEAR(r["list"][1]["error_m"].get<double>(), 0.0, 1e-9);

  // Within the bounds (0.15 m, 3°) a relation condemns nothing.
  ClosureJudge slightly = run.truthJudge("slightly");
  *slightly.reference[2] = *slightly.reference[2] * Pose2{0.1, 0.0, 2.5 * kDeg};
  r = judgeClosures(closures, {}, run.judged, {slightly}, {relation(1, 2)});
  EXPECT_EQ(r["judge_poses_contradicted"], 0);
  EXPECT_EQ(r["closures_judged"], 2);

  // A scan without a pose of its own borrows none from a condemned one.
  ClosureJudge sparse = run.truthJudge("sparse");
  sparse.reference[3].reset();
  *sparse.reference[2] = *sparse.reference[2] * Pose2{0.0, 0.0, 7.0 * kDeg};
  ClosureJudge marked = sparse;
  EXPECT_EQ(markContradictedPoses(marked, {relation(1, 2)}, run.judged), 2u);
  EXPECT_TRUE(sparse.referenceOf(3, run.judged.laser_poses).has_value());
  EXPECT_FALSE(marked.referenceOf(3, run.judged.laser_poses).has_value()) << "scan 3 borrows scan 2's pose";
  EXPECT_TRUE(marked.referenceOf(4, run.judged.laser_poses).has_value());
}

// The relations judge on their own, chained from the match to the query
// (RelationChain), with the bounds a judge's poses have.
TEST(ClosureJudge, TheRelationsJudgeTheClosuresTheyChainTo) {
  const TenScanRun run;
  const std::vector<slam2d::LoopClosure2d> closures = {
      run.closure(8, 2), run.closure(7, 1, {0.0, 0.35, 0.0}), run.closure(9, 3, {0.0, 0.0, 6.0 * kDeg})};
  nlohmann::json r = judgeClosures(closures, {}, run.judged, {run.truthJudge("truth")});
  EXPECT_TRUE(r["false_by_relations"].is_null()) << "no relations";
  EXPECT_EQ(r["closures_judged_by_relations"], 0);
  EXPECT_FALSE(r["list"][0].contains("by_relations"));

  std::vector<datasets::SlamRelation> relations;
  for (size_t i = 0; i + 1 < 10; ++i)
    relations.push_back({run.judged.stamps_ns[i], run.judged.stamps_ns[i + 1],
                         between(run.judged.laser_poses[i], run.judged.laser_poses[i + 1]), 0});
  r = judgeClosures(closures, {}, run.judged, {run.truthJudge("truth")}, relations);
  EXPECT_EQ(r["closures_judged_by_relations"], 3);
  EXPECT_EQ(r["false_by_relations"], 2);
  const nlohmann::json& list = r["list"];
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR(list[k]["by_relations"]["error_m"].get<double>(), list[k]["error_m"].get<double>(), 1e-9);
    EXPECT_NEAR(list[k]["by_relations"]["error_deg"].get<double>(), list[k]["error_deg"].get<double>(), 1e-6);
    EXPECT_EQ(list[k]["by_relations"]["false"], list[k]["false"]);
    EXPECT_EQ(list[k]["by_relations"]["bridge_scans"], 0);
  }
  EXPECT_EQ(list[0]["by_relations"]["relations"], 6);
  EXPECT_NEAR(r["worst_error_by_relations_m"].get<double>(), list[1]["error_m"].get<double>(), 1e-9);

  // Without a corrected log the relations still judge.
  r = judgeClosures(closures, {}, run.judged, {}, relations);
  EXPECT_TRUE(r["false_closures"].is_null());
  EXPECT_EQ(r["false_by_relations"], 2);
}

// A long chain of relations gathers their errors: a false verdict by the
// relations is checked against the scans as a judge's is, the match's local
// map drawn by the estimate.
TEST(ClosureJudge, TheScansShowWhetherAFalseVerdictIsTheRelationsError) {
  JudgedRun run = outAndBackAmongLandmarks(11);
  const auto chainOfSteps = [&](const Pose2& error_at_turn) {
    std::vector<datasets::SlamRelation> relations;
    for (size_t i = 0; i + 1 < 40; ++i)
      relations.push_back({run.stamps_ns[i], run.stamps_ns[i + 1],
                           between(run.laser_poses[i], run.laser_poses[i + 1]) * (i == 19 ? error_at_turn : Pose2{}), 0});
    return relations;
  };
  // A true closure, and relations off by 0.4 m at the turn their chain passes.
  const std::vector<slam2d::LoopClosure2d> true_closure = {closureOf(run, 39, 0, {})};
  nlohmann::json r = judgeClosures(true_closure, {}, run, {}, chainOfSteps({0.0, 0.4, 0.0}));
  EXPECT_EQ(r["false_by_relations"], 1);
  EXPECT_EQ(r["false_by_relations_confirmed_by_scans"], 0);
  const nlohmann::json& verdict = r["list"][0]["by_relations"];
  EXPECT_FALSE(verdict["confirmed_by_scans"].get<bool>());
  EXPECT_LT(verdict["scan_fit_closure_m"].get<double>(), 1e-9);
  EXPECT_GT(verdict["scan_fit_relations_m"].get<double>(), 0.1);
  // A closure truly 0.4 m off, exact relations: the scans confirm the verdict.
  const std::vector<slam2d::LoopClosure2d> false_closure = {closureOf(run, 38, 1, {0.4, 0.0, 0.0})};
  r = judgeClosures(false_closure, {}, run, {}, chainOfSteps({}));
  EXPECT_EQ(r["false_by_relations"], 1);
  EXPECT_EQ(r["false_by_relations_confirmed_by_scans"], 1);
  EXPECT_TRUE(r["list"][0]["by_relations"]["confirmed_by_scans"].get<bool>());
  // Without scans, no check.
  run.scan_points.clear();
  r = judgeClosures(false_closure, {}, run, {}, chainOfSteps({}));
  EXPECT_EQ(r["false_by_relations"], 1);
  EXPECT_TRUE(r["false_by_relations_confirmed_by_scans"].is_null());
  EXPECT_FALSE(r["list"][0]["by_relations"].contains("confirmed_by_scans"));
}

TEST(ClosureJudge, ScansSharingAStampAreNotJudged) {
  TenScanRun run;
  run.judged.stamps_ns[2] = run.judged.stamps_ns[3];  // a log with rounded stamps
  const nlohmann::json r = judgeClosures({run.closure(8, 3), run.closure(8, 4)}, {}, run.judged, {run.truthJudge("truth")});
  EXPECT_EQ(r["closures_judged"], 1);
  EXPECT_FALSE(r["list"][0].contains("error_m"));
  EXPECT_TRUE(r["list"][1].contains("error_m"));
  EXPECT_EQ(uniqueStampIndex(run.judged.stamps_ns).count(run.judged.stamps_ns[3]), 0u);
  EXPECT_EQ(uniqueStampIndex(run.judged.stamps_ns).at(run.judged.stamps_ns[4]), 4u);
}

// Two corrections of one run, one in another frame and with one bad pose:
// after bringing one onto the other, the bad scan stands out, and the
// estimate shows which of the two it agrees with there.
TEST(ClosureJudge, JudgesAgreementFindsTheScanWhereTwoCorrectionsDisagree) {
  const TenScanRun run;
  const ClosureJudge first = run.truthJudge("first");
  ClosureJudge other = run.truthJudge("other");
  const Pose2 frame{5.0, -2.0, 30.0 * kDeg};
  for (auto& p : other.reference) p = frame * *p;
  *other.reference[2] = *other.reference[2] * Pose2{0.0, 0.0, 12.0 * kDeg};
  other.reference[7].reset();  // not in common
  const nlohmann::json a = judgesAgreement(run.judged, first, other, 2);
  EXPECT_EQ(a["common_scans"], 9);
  EXPECT_EQ(a["scans_within_3deg"], 8);
  EXPECT_NEAR(a["heading_diff_deg"]["median"].get<double>(), 0.0, 1e-6);
  EXPECT_NEAR(a["heading_diff_deg"]["max"].get<double>(), 12.0, 1e-6);
  ASSERT_EQ(a["worst"].size(), 2u);
  const nlohmann::json& bad = a["worst"][0];
  EXPECT_EQ(bad["stamp_ns"], run.judged.stamps_ns[2]);
  EXPECT_NEAR(std::abs(bad["heading_diff_deg"].get<double>()), 12.0, 1e-6);
  EXPECT_NEAR(bad["estimate_vs_first_deg"].get<double>(), 0.0, 1e-6);  // the estimate sides with the first
  EXPECT_NEAR(std::abs(bad["estimate_vs_other_deg"].get<double>()), 12.0, 1e-6);
  EXPECT_NEAR(a["worst"][1]["heading_diff_deg"].get<double>(), 0.0, 1e-6);
  EXPECT_LT(a["worst"][1]["position_diff_m"].get<double>(), 0.01);  // only scan 2's heading is off
}

}  // namespace
}  // namespace rmap::bench
