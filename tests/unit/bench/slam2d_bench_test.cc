#include "slam2d/slam2d_bench.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

namespace rmap::bench {
namespace {

namespace fs = std::filesystem;

fs::path tempPath(const std::string& name) {
  return fs::temp_directory_path() / ("rmap_slam2d_bench_" + std::to_string(::getpid()) + "_" + name);
}

// End to end on a short simulated run: every field the issue asks for, the
// SLAM close to the truth, and figures that agree with each other.
TEST(Slam2dBench, SimulatedRunReportsConsistentFigures) {
  Slam2dBenchOptions o;
  o.source = "sim:building";
  o.sim.poses = 150;
  o.json_out = tempPath("sim.json").string();
  o.poses_out = tempPath("sim.poses").string();
  ASSERT_EQ(runSlam2dBench(o), 0);
  std::ifstream in(o.json_out);
  const nlohmann::json r = nlohmann::json::parse(in);
  for (const char* key : {"dataset", "scans", "relations_used", "rel_trans_err_m", "rel_rot_err_deg",
                          "ate_vs_reference_m", "rpe_1m_m", "realtime_factor", "cpu_s", "ate_vs_truth_m",
                          "reflectivity_rel_err_median", "reflectivity_spread_raw", "reflectivity_spread_calibrated"}) {
    EXPECT_TRUE(r.contains(key)) << key;
  }
  const size_t scans = r["scans"].get<size_t>();
  EXPECT_GE(scans, 150u);  // plus turns on the spot
  EXPECT_EQ(r["scans_rejected"], 0);
  EXPECT_EQ(r["non_finite_poses"], 0);
  EXPECT_EQ(r["poses_outside_map"], 0);
  EXPECT_GT(r["relations_used"].get<size_t>(), 0u);
  EXPECT_EQ(r["relations_used"], r["relations_total"]);
  EXPECT_LT(r["ate_vs_truth_m"].get<double>(), 0.1);
  EXPECT_EQ(r["ate_vs_truth_m"], r["ate_vs_reference_m"]);
  EXPECT_LT(r["rel_trans_err_m"]["mean"].get<double>(), 0.05);
  EXPECT_GE(r["rel_trans_err_m"]["std"].get<double>(), 0.0);
  EXPECT_NEAR(r["reference_rel_trans_err_m"]["max"].get<double>(), 0.0, 1e-9);  // the truth scores itself exactly
  EXPECT_NEAR(r["realtime_factor"].get<double>(), r["log_duration_s"].get<double>() / r["wall_s"].get<double>(), 1e-9);
  EXPECT_NEAR(r["log_duration_s"].get<double>(), 0.1 * double(scans - 1), 1e-9);
  EXPECT_GT(r["cpu_s"].get<double>(), 0.0);
  // the self-calibrated map: close to the true reflectivity, and calibration
  // removes most of the viewpoint dependence of the raw readings
  EXPECT_LT(r["reflectivity_rel_err_median"].get<double>(), 0.05);
  EXPECT_GT(r["reflectivity"]["cells_compared"].get<size_t>(), 100u);
  EXPECT_GT(r["reflectivity_spread_raw"].get<double>(), 5 * r["reflectivity_spread_calibrated"].get<double>());
  // The short tour never comes back: no revisit to check, said so rather than scored 0.
  EXPECT_EQ(r["revisit_consistency"]["pairs"], 0);
  EXPECT_TRUE(r["revisit_consistency"]["residual_m"].is_null());
  std::ifstream poses(o.poses_out);
  size_t lines = 0;
  for (std::string line; std::getline(poses, line);) ++lines;
  EXPECT_EQ(lines, scans);
  fs::remove(o.json_out);
  fs::remove(o.poses_out);
}

// --repeat: the same run from other starts, each scored; the first is the headline run.
// The whole simulated tour comes back through its building: the run's scans lie on each other
// there about as well as under the true poses, whose residual is the sensor noise alone.
TEST(Slam2dBench, ReportsHowWellRevisitsAgree) {
  Slam2dBenchOptions o;
  o.source = "sim:building";
  o.sim.poses = 600;
  o.json_out = tempPath("revisits.json").string();
  o.revisits_out = tempPath("revisits.txt").string();
  ASSERT_EQ(runSlam2dBench(o), 0);
  std::ifstream in(o.json_out);
  const nlohmann::json c = nlohmann::json::parse(in)["revisit_consistency"];
  fs::remove(o.json_out);
  // The list holds each revisit the figures came from: its residuals square-average to them.
  std::ifstream list(o.revisits_out);
  std::string header;
  std::getline(list, header);
  EXPECT_EQ(header, "# earlier_stamp_s later_stamp_s earlier_scan later_scan points run_residual_m reference_residual_m");
  size_t rows = 0;
  double run_sq = 0.0, reference_sq = 0.0;
  for (double earlier_s, later_s, earlier_scan, later_scan, points, run_m, reference_m;
       list >> earlier_s >> later_s >> earlier_scan >> later_scan >> points >> run_m >> reference_m;) {
    ++rows;
    EXPECT_LT(earlier_s, later_s);
    EXPECT_LT(earlier_scan, later_scan);
    // The simulated scans come at 10 Hz: the indices and the stamps tell the same span.
    EXPECT_NEAR(later_s - earlier_s, 0.1 * (later_scan - earlier_scan), 1e-6);
    EXPECT_GT(points, 0.0);
    run_sq += run_m * run_m;
    reference_sq += reference_m * reference_m;
  }
  fs::remove(o.revisits_out);
  ASSERT_EQ(rows, c["against_reference"]["pairs"].get<size_t>());
  EXPECT_NEAR(std::sqrt(run_sq / double(rows)), c["against_reference"]["residual_m"].get<double>(), 1e-4);
  EXPECT_NEAR(std::sqrt(reference_sq / double(rows)), c["against_reference"]["reference_residual_m"].get<double>(), 1e-4);
  EXPECT_GT(c["pairs"].get<size_t>(), 50u);
  const nlohmann::json& both = c["against_reference"];
  ASSERT_FALSE(both.is_null()) << "the truth covers every scan";
  EXPECT_EQ(both["lowest_estimate"].get<size_t>() + both["lowest_reference"].get<size_t>(), both["pairs"].get<size_t>());
  EXPECT_GT(both["lowest_reference"].get<size_t>(), both["lowest_estimate"].get<size_t>()) << "the truth fits more revisits";
  EXPECT_GT(both["reference_residual_m"].get<double>(), 0.005) << "sensor noise";
  EXPECT_LT(both["reference_residual_m"].get<double>(), 0.06);
  EXPECT_NEAR(both["residual_m"].get<double>(), both["reference_residual_m"].get<double>(), 0.01);
  EXPECT_NEAR(c["residual_m"].get<double>(), both["residual_m"].get<double>(), 0.01);
}

TEST(Slam2dBench, RepeatedRunsStartElsewhereAndAreEachScored) {
  Slam2dBenchOptions o;
  o.source = "sim:building";
  o.sim.poses = 80;
  o.repeat = 3;
  o.json_out = tempPath("repeat.json").string();
  ASSERT_EQ(runSlam2dBench(o), 0);
  std::ifstream in(o.json_out);
  const nlohmann::json r = nlohmann::json::parse(in);
  ASSERT_TRUE(r.contains("repeated"));
  const nlohmann::json& runs = r["repeated"]["runs"];
  ASSERT_EQ(runs.size(), 3u);
  EXPECT_EQ(runs[0]["ate_m"], r["ate_vs_reference_m"]);
  EXPECT_EQ(runs[0]["start"], nlohmann::json::array({0.0, 0.0, 0.0}));
  std::vector<double> ate;
  for (size_t k = 0; k < runs.size(); ++k) {
    ate.push_back(runs[k]["ate_m"].get<double>());
    EXPECT_LT(ate.back(), 0.1) << "run " << k << ": the simulated run is easy from any start";
    EXPECT_GT(runs[k]["cpu_s"].get<double>(), 0.0);
  }
  for (size_t k : {1u, 2u}) {
    EXPECT_NE(runs[k]["start"], runs[0]["start"]);
    EXPECT_NE(ate[k], ate[0]) << "run " << k << " was not moved: the grid lay as in the first";
  }
  std::sort(ate.begin(), ate.end());
  EXPECT_EQ(r["repeated"]["ate_m_median"].get<double>(), ate[1]);
  EXPECT_EQ(r["repeated"]["ate_m_min"].get<double>(), ate[0]);
  EXPECT_EQ(r["repeated"]["ate_m_max"].get<double>(), ate[2]);
  // The simulation has relations: their error is spread over the runs too.
  EXPECT_LE(r["repeated"]["rel_trans_err_m_min"].get<double>(), r["repeated"]["rel_trans_err_m_median"].get<double>());
  EXPECT_LE(r["repeated"]["rel_trans_err_m_median"].get<double>(), r["repeated"]["rel_trans_err_m_max"].get<double>());
  fs::remove(o.json_out);
}

/// A corrected-log layout: each scan's corrected pose, then ODOM restarting from it.
std::string correctedLog() {
  std::ostringstream log;
  for (int k = 0; k < 6; ++k) {
    const double x = 0.3 * k + 0.05 * (k % 2);  // the correction wobbles, the wheels do not
    log << "FLASER 4 2 2 2 2 " << x << " 0 0 " << x << " 0 0 " << k << ".0 h 0\n";
    log << "ODOM " << x << " 0 0 0 0 0 " << k << ".05 h 0\n";
    log << "ODOM " << x + 0.3 << " 0 0 0 0 0 " << k << ".1 h 0\n";
  }
  return log.str();
}

TEST(Slam2dBench, CorrectedLogsGiveOnlyWheelIncrements) {
  const fs::path path = tempPath("corrected.log");
  std::ofstream(path) << correctedLog();
  const Slam2dDataset d = loadSlam2dDataset(path.string(), {});
  ASSERT_EQ(d.inputs.size(), 6u);
  EXPECT_EQ(d.reference_kind, "corrected poses of the log");
  EXPECT_EQ(d.odometry_kind, "increments of the ODOM lines");
  for (size_t k = 0; k < 6; ++k) {
    ASSERT_TRUE(d.inputs[k].odometry);
    EXPECT_NEAR(d.inputs[k].odometry->x_m, 0.3 * double(k), 1e-9) << k;  // none of the 0.05 m wobble
    ASSERT_TRUE(d.reference[k]);
    EXPECT_NEAR(d.reference[k]->x_m, 0.3 * k + 0.05 * (k % 2), 1e-9) << k;
  }
  EXPECT_NEAR(*d.duration_s, 5.0, 1e-9);
  // The corrected poses are the reference: refusing them as odometry.
  Slam2dSourceOptions o;
  o.odometry = OdometrySource::kLogged;
  EXPECT_THROW(loadSlam2dDataset(path.string(), o), std::runtime_error);
  o.odometry = OdometrySource::kNone;
  EXPECT_FALSE(loadSlam2dDataset(path.string(), o).inputs[3].odometry);
  fs::remove(path);
}

TEST(Slam2dBench, ReferenceLogMatchesOnStamps) {
  const fs::path path = tempPath("raw.log"), reference = tempPath("reference.log");
  std::ofstream(path) << correctedLog();
  // the reference holds scans 1 and 4 only, with other poses
  std::ofstream(reference) << "FLASER 2 1 1 7 8 0.5 7 8 0.5 1.0 h 0\nFLASER 2 1 1 9 8 0.5 9 8 0.5 4.0 h 0\n";
  Slam2dSourceOptions o;
  o.reference_path = reference.string();
  const Slam2dDataset d = loadSlam2dDataset(path.string(), o);
  ASSERT_EQ(d.reference.size(), 6u);
  for (size_t k : {0, 2, 3, 5}) EXPECT_FALSE(d.reference[k]) << k;
  ASSERT_TRUE(d.reference[1] && d.reference[4]);
  EXPECT_EQ(d.reference[1]->x_m, 7.0);
  EXPECT_EQ(d.reference[4]->x_m, 9.0);
  EXPECT_EQ(d.reference_kind, "poses of " + reference.filename().string() + " at 2 shared stamps");
  std::ofstream(reference) << "FLASER 2 1 1 7 8 0.5 7 8 0.5 11.0 h 0\n";
  EXPECT_THROW(loadSlam2dDataset(path.string(), o), std::runtime_error);
  fs::remove(path);
  fs::remove(reference);
}

TEST(Slam2dBench, StampsFromTheLogHoldingTheSameScans) {
  const fs::path path = tempPath("subset.log"), raw = tempPath("raw.log");
  std::ofstream(path) << "FLASER 3 1 2 3.5 0 0 0 0 0 0 0.5 h 0\nFLASER 3 1 2 4 0 0 0 0 0 0 0.6 h 0\n";
  // The raw log has the second scan (to the millimetre) and others, under its
  // own stamps; its largest reading is higher, so 4 is a return there but a
  // no return in the subset, and must still match.
  std::ofstream(raw) << "FLASER 3 1 2 3.5 0 0 0 0 0 0 976052857.3 h 0\n"
                        "FLASER 3 1.0001 2 4 0 0 0 0 0 0 976052857.337284 h 0\n"
                        "FLASER 3 1 3 5 0 0 0 0 0 0 976052858.0 h 0\n"
                        "FLASER 3 1 2 3.5 0 0 0 0 0 0 976052859.0 h 0\n";
  Slam2dSourceOptions o;
  o.stamps_path = raw.string();
  const Slam2dDataset d = loadSlam2dDataset(path.string(), o);
  EXPECT_EQ(d.stamps_replaced, 1u);
  EXPECT_EQ(d.inputs[0].scan.stamp_ns, 500000000);  // twice in the raw log: ambiguous, kept
  EXPECT_EQ(d.inputs[1].scan.stamp_ns, 976052857337284000);
  std::ofstream(raw) << "FLASER 3 9 9 9 0 0 0 0 0 0 1 h 0\n";
  EXPECT_THROW(loadSlam2dDataset(path.string(), o), std::runtime_error);
  fs::remove(path);
  fs::remove(raw);
}

// A log whose stamps do not tell its scans apart (printed with 6 significant
// digits, or 0) is numbered instead, so its closures can be judged; one whose
// stamps do is left alone, and so is a log whose stamps come from another.
TEST(Slam2dBench, ScansOfALogWithoutDistinctStampsAreNumbered) {
  const fs::path path = tempPath("stampless.log"), stamped = tempPath("stamped.log");
  std::ofstream(path) << "FLASER 3 1 2 3 0 0 0 0 0 0 1.01893e+09 h 1.01893e+09\n"
                         "FLASER 3 2 3 4 1 0 0 1 0 0 1.01893e+09 h 1.01893e+09\n"
                         "FLASER 3 3 4 5 2 0 0 2 0 0 1.01893e+09 h 1.01893e+09\n";
  std::ofstream(stamped) << "FLASER 3 1 2 3 0 0 0 0 0 0 0.5 h 0\nFLASER 3 2 3 4 1 0 0 1 0 0 0.6 h 0\n"
                            "FLASER 3 3 4 5 2 0 0 2 0 0 0.6 h 0\n";
  const Slam2dDataset numbered = loadSlam2dDataset(path.string(), {});
  EXPECT_TRUE(numbered.scans_numbered);
  ASSERT_EQ(numbered.inputs.size(), 3u);
  for (size_t k = 0; k < 3; ++k) EXPECT_EQ(numbered.inputs[k].scan.stamp_ns, int64_t(k));
  EXPECT_FALSE(numbered.duration_s) << "the numbers measure no time";
  const Slam2dDataset kept = loadSlam2dDataset(stamped.string(), {});
  EXPECT_FALSE(kept.scans_numbered) << "two distinct stamps of three tell most scans apart";
  EXPECT_EQ(kept.inputs[2].scan.stamp_ns, 600000000);
  Slam2dSourceOptions from_stamped;
  from_stamped.stamps_path = stamped.string();
  const Slam2dDataset taken = loadSlam2dDataset(path.string(), from_stamped);
  EXPECT_FALSE(taken.scans_numbered);
  EXPECT_EQ(taken.inputs[0].scan.stamp_ns, 500000000);
  fs::remove(path);
  fs::remove(stamped);
}

// A corrected log run with --stamps-from carries the raw log's stamps: a
// second correction judging its closures must find its scans there too.
TEST(Slam2dBench, ClosureJudgesFindTheirScansWhereTheRunsStampsCameFrom) {
  const fs::path run_log = tempPath("run.log"), raw = tempPath("raw.log"), judge_log = tempPath("judge.log");
  std::ofstream(raw) << "FLASER 3 1 2 3 0 0 0 0 0 0 976052857.1 h 0\n"
                        "FLASER 3 2 3 4 0 0 0 0 0 0 976052857.2 h 0\n"
                        "FLASER 3 3 4 5 0 0 0 0 0 0 976052857.3 h 0\n";
  std::ofstream(run_log) << "FLASER 3 1 2 3 0 0 0 0 0 0 0.5 h 0\nFLASER 3 2 3 4 1 0 0 1 0 0 0.6 h 0\n"
                            "FLASER 3 3 4 5 2 0 0 2 0 0 0.7 h 0\n";
  std::ofstream(judge_log) << "FLASER 3 2 3 4 7 8 0.5 7 8 0.5 5.0 h 0\nFLASER 3 3 4 5 9 8 0.5 9 8 0.5 6.0 h 0\n";
  for (const bool stamps_from_raw : {true, false}) {
    Slam2dBenchOptions options;
    options.source = run_log.string();
    if (stamps_from_raw) options.stamps_path = raw.string();
    options.closure_reference_paths = {judge_log.string()};
    Slam2dSourceOptions source;
    source.stamps_path = options.stamps_path;
    const Slam2dDataset data = loadSlam2dDataset(run_log.string(), source);
    EXPECT_EQ(data.inputs[1].scan.stamp_ns, stamps_from_raw ? 976052857200000000 : 600000000);
    const std::vector<ClosureJudge> judges = closureJudges(options, data);
    ASSERT_EQ(judges.size(), 1u);
    ASSERT_EQ(judges[0].reference.size(), 3u);
    EXPECT_FALSE(judges[0].reference[0]) << stamps_from_raw;
    ASSERT_TRUE(judges[0].reference[1] && judges[0].reference[2]) << stamps_from_raw;
    EXPECT_EQ(judges[0].reference[1]->x_m, 7.0);
    EXPECT_EQ(judges[0].reference[2]->x_m, 9.0);
  }
  fs::remove(run_log);
  fs::remove(raw);
  fs::remove(judge_log);
}

// A log whose stamps were rewritten (scans 0.9 s apart) takes relations whose
// scans were 0.44 s apart by counting: gaps rounded to whole periods (jitter
// of a few hundredths is the real logs'), the earliest at the given scan.
TEST(Slam2dBench, RelationsArePlacedByCountingScanPeriods) {
  const fs::path log = tempPath("rewritten.log"), rel = tempPath("rewritten.relations");
  std::ofstream(log) << "FLASER 3 1 2 3 0 0 0 0 0 0 50.0 h 0\nFLASER 3 1 2 3 0 0 0 0 0 0 50.9 h 0\n"
                        "FLASER 3 1 2 3 0 0 0 0 0 0 51.8 h 0\nFLASER 3 1 2 3 0 0 0 0 0 0 52.7 h 0\n"
                        "FLASER 3 1 2 3 0 0 0 0 0 0 53.6 h 0\n";
  std::ofstream(rel) << "1000.000 1000.880 0.9 0 0 0 0 0\n"   // 2 periods
                        "1000.880 1001.319 0.4 0 0 0 0 0.1\n"  // 1 period, 0.001 s short
                        "1001.319 1002.650 1.2 0 0 0 0 0\n";   // 3 more: past the last scan
  Slam2dSourceOptions o;
  o.relations_path = rel.string();
  const Slam2dDataset by_stamp = loadSlam2dDataset(log.string(), o);
  ASSERT_EQ(by_stamp.relations.size(), 3u);
  EXPECT_EQ(by_stamp.relations[0].from_stamp_ns, 1'000'000'000'000) << "without a period the stamps stay";
  o.relations_scan_period_s = 0.44;
  o.relations_first_scan = 1;
  const Slam2dDataset counted = loadSlam2dDataset(log.string(), o);
  EXPECT_EQ(counted.relations_dropped, 1u);
  ASSERT_EQ(counted.relations.size(), 2u);
  EXPECT_EQ(counted.relations[0].from_stamp_ns, 50'900'000'000);  // scan 1
  EXPECT_EQ(counted.relations[0].to_stamp_ns, 52'700'000'000);    // scan 3
  EXPECT_EQ(counted.relations[1].from_stamp_ns, 52'700'000'000);
  EXPECT_EQ(counted.relations[1].to_stamp_ns, 53'600'000'000);    // scan 4
  EXPECT_DOUBLE_EQ(counted.relations[1].motion.theta_rad, 0.1);
  // A gap half a period off whole: the period is wrong, say so.
  std::vector<datasets::SlamRelation> off = by_stamp.relations;
  off[1].to_stamp_ns = off[1].from_stamp_ns + 660'000'000;
  off[2].from_stamp_ns = off[1].to_stamp_ns;
  EXPECT_THROW(placeRelationsByScanPeriod(off, counted.inputs, 0.44, 0), std::invalid_argument);
  EXPECT_THROW(placeRelationsByScanPeriod(off, counted.inputs, 0.0, 0), std::invalid_argument);
  fs::remove(log);
  fs::remove(rel);
}

TEST(Slam2dBench, BadSourcesAreClearErrors) {
  EXPECT_THROW(loadSlam2dDataset("sim:nowhere", {}), std::runtime_error);
  EXPECT_THROW(loadSlam2dDataset("/nonexistent/log.gz", {}), std::runtime_error);
  EXPECT_THROW(parseOdometrySource("wheels"), std::invalid_argument);
  Slam2dSourceOptions o;
  o.sim.laser = "lidar9000";
  EXPECT_THROW(loadSlam2dDataset("sim:building", o), std::runtime_error);
}

}  // namespace
}  // namespace rmap::bench
