#pragma once
/// @file loop_bench.h
/// `rmap-bench loop`: runs the place recogniser (server/loop) over an image
/// folder in frame order and scores it against ground-truth loop pairs
/// (loop_scoring.h) at tolerances 0, 2 and 40 frames; times every frame
/// (feature extraction included, image decoding excluded) on one OpenCV
/// thread unless told otherwise.
///
/// Outputs: a summary on stdout; --json; with --csv-prefix P: P_pr_tol<k>.csv
/// (threshold, precision, recall, declared, correct), P_frames.csv (per
/// frame: ms, vocabulary words, best reference, score, accepted) and
/// P_pr.png (the three precision–recall curves).

#include <cstdint>
#include <string>
#include <vector>

#include "loop/loop_detector.h"

namespace rmap::bench {

struct LoopBenchOptions {
  std::string images_dir;        ///< image files in frame order (sorted by name)
  std::string ground_truth;      ///< `query reference` pairs; empty: timing only
  std::string json_out;          ///< empty: no file
  std::string csv_prefix;        ///< empty: no CSV / PNG
  std::string descriptor = "orb";  ///< orb | brisk | akaze
  int max_features = 500;
  int resize_width = 0;          ///< > 0 with resize_height: frames resized to this size first (timing at other sizes)
  int resize_height = 0;
  size_t max_frames = 0;         ///< 0: all
  int threads = 1;               ///< OpenCV threads (1: one core)
  std::vector<int64_t> tolerances{0, 2, 40};
  loop::LoopDetectorOptions detector;
};

/// The image files of a folder (png, jpg, jpeg, pgm, ppm, bmp, tif, tiff), sorted by name.
/// @throws std::runtime_error when the folder cannot be read or holds no image
std::vector<std::string> listImages(const std::string& dir);

/// Runs, prints a summary, writes the files. @return process exit code
int runLoopBench(const LoopBenchOptions& options);

}  // namespace rmap::bench
