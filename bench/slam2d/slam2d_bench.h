#pragma once
/// @file slam2d_bench.h
/// `rmap-bench slam2d`: runs the 2D SLAM on a CARMEN log or a simulated run
/// and scores it (relation error, ATE, RPE, speed; reflectivity on simulation).

#include <string>
#include <vector>

#include "slam2d/closure_judge.h"
#include "slam2d/slam2d.h"
#include "slam2d/slam2d_dataset.h"

namespace rmap::bench {

struct Slam2dBenchOptions {
  std::string source;          ///< see loadSlam2dDataset
  std::string relations_path;  ///< Kümmerle relation file, or empty
  std::string reference_path;  ///< CARMEN log of reference poses at the same stamps, or empty (see Slam2dSourceOptions)
  std::string stamps_path;     ///< CARMEN log to take the scans' stamps from, or empty (see Slam2dSourceOptions)
  double relations_scan_period_s = 0.0;  ///< > 0: relations placed by counting scan periods (see Slam2dSourceOptions)
  size_t relations_first_scan = 0;       ///< the scan of the relations' earliest stamp, with relations_scan_period_s
  std::string odometry = "auto";  ///< auto | logged | odom-increments | none (see OdometrySource)
  std::string json_out;        ///< empty: no file
  std::string poses_out;       ///< empty: no file; else one line "stamp_s x y theta" per scan (estimated laser pose)
  /// empty: no file; else a '#' header line and one line per revisit of the revisit residual (see
  /// revisit_consistency.h), "earlier_stamp_s later_stamp_s points run_residual_m
  /// [reference_residual_m]", scored with the reference when it has a pose for every scan
  std::string revisits_out;
  std::string map_image_out;   ///< empty: no file; else the final occupancy grid, 8-bit (format by extension: .png, .pgm)
  int map_image_max_px = 100000;  ///< the image is scaled down so its longer side is at most this
  /// Corrected logs of the same run (e.g. intel-corrected for raw intel):
  /// the poses of each, found by their scans' ranges, judge each accepted
  /// closure (a closure is false when its relative pose is off by > 0.3 m or
  /// 5°); the first gives the headline figures. Two corrections of one run
  /// can disagree (raw mit-csail, BENCHMARKS.md §4), so each judge's verdict
  /// is reported. Empty: closures are judged against the reference poses
  /// where known.
  std::vector<std::string> closure_reference_paths;
  size_t max_scans = 0;        ///< 0: all; else only the first ones (quick runs)
  /// Runs of the log: the first as it is, the others from other starts (the whole run moved by
  /// a seeded rigid motion: up to 1 m, any heading), each scored the same way; the JSON's
  /// `repeated` gives each and the median ATE. One run's figures on the sparse logs can move a
  /// lot with where the grid lies under it (docs/BENCHMARKS.md §4); the median does not.
  int repeat = 1;
  /// The run moved to this start (x m, y m, θ rad) as --repeat moves its runs: one of them
  /// reproduced in full detail (not with repeat > 1). Empty: as logged.
  std::vector<double> start;
  double rpe_distance_m = 1.0;
  Slam2dSimOptions sim;
  slam2d::Slam2dOptions slam;  ///< the engine's defaults unless set on the command line
};

/// The closure judges of a run of `data`: each of closure_reference_paths
/// (its scans found by their ranges in the log whose stamps the run's scans
/// carry: stamps_path when given, else source), else the reference poses
/// (none for raw odometry).
std::vector<ClosureJudge> closureJudges(const Slam2dBenchOptions& options, const Slam2dDataset& data);

/// Runs, prints a summary, writes JSON. @return process exit code
int runSlam2dBench(const Slam2dBenchOptions& options);

}  // namespace rmap::bench
