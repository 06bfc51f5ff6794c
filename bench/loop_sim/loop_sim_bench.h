#pragma once
/// @file loop_sim_bench.h
/// `rmap-bench loop-sim`: the place recogniser on a simulated revisit
/// sequence (sim_sequence.h) of camera images or laser-intensity panoramas,
/// scored against the true loops (precision, recall, recall at 100 %
/// precision at frame tolerances 0, 2, 40). Times the detector per frame
/// (feature extraction included; rendering and projection reported apart), on
/// one OpenCV thread.
///
/// `rmap-bench loop-compare`: projection models (equirectangular,
/// ring-by-column) × descriptors (ORB, BRISK, AKAZE) on the simulated lidar
/// panoramas (the same scans for every cell of the table), plus a sanity check
/// on a real lidar pair (lidar-intensity/small-gicp-pair): features of the two
/// scans' panoramas matched (mutual nearest Hamming), and the share of matches
/// whose 3D points agree under the known transform, next to the chance share
/// (the same keypoints paired with another match's target).

#include <cstdint>
#include <string>
#include <vector>

#include "loop/loop_detector.h"
#include "loop/panorama.h"
#include "loop_sim/sim_sequence.h"

namespace rmap::bench {

struct LoopSimBenchOptions {
  std::string modality = "camera";         ///< camera | laser
  bool dark = false;                       ///< revisit laps in the dark (camera; laser unaffected)
  std::string projection = "equirectangular";  ///< laser: equirectangular | ring
  std::string descriptor = "orb";          ///< orb | brisk | akaze
  std::string verification = "rigid3d";   ///< laser: rigid3d (rmapd's loop::panoramaDetectorOptions) | fundamental (`detector`)
  std::string json_out;
  SimSequenceOptions sequence;
  loop::PanoramaOptions panorama;          ///< laser; ring_count defaults to the lidar's rings
  loop::LoopDetectorOptions detector;
  std::vector<int64_t> tolerances{0, 2, 40};
  int threads = 1;                         ///< OpenCV threads
};

struct LoopCompareOptions {
  SimSequenceOptions sequence;
  loop::PanoramaOptions panorama;          ///< projection and ring_count are set per row
  loop::LoopDetectorOptions detector;
  int64_t tolerance = 0;                   ///< frames, for the table's recall at 100 % precision
  std::string lidar_pair_dir;              ///< real pair folder ('' skips the sanity check)
  double agree_m = 0.5;                    ///< real pair: matched 3D points this close under the transform agree
  std::string json_out;
  int threads = 1;
};

/// Parses a projection name: "equirectangular" | "ring". @throws std::invalid_argument
loop::PanoramaProjection projectionFromString(const std::string& name);

/// @return process exit code
int runLoopSimBench(const LoopSimBenchOptions& options);
int runLoopCompareBench(const LoopCompareOptions& options);

}  // namespace rmap::bench
