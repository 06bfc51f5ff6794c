#pragma once
/// @file detector_run.h
/// Runs a LoopDetector over a frame sequence and scores it (loop_scoring.h):
/// shared by `rmap-bench loop-sim` and `loop-compare`.

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "loop/loop_detector.h"
#include "loop/loop_scoring.h"

namespace rmap::bench {

struct DetectorRun {
  std::vector<LoopDeclaration> swept;     ///< every frame's best verified candidate
  std::vector<LoopDeclaration> accepted;  ///< those the detector accepted
  std::vector<double> wall_ms;            ///< per frame, addFrame (feature extraction included)
  std::vector<double> cpu_ms;             ///< per frame, thread CPU time of the same
  size_t vocabulary_words = 0;
};

/// Feeds frames 0..n−1 (from `frame`, not timed) to a detector with `descriptor` features.
DetectorRun runDetector(const std::function<loop::PlaceImage(size_t)>& frame, size_t n, loop::DescriptorType descriptor,
                        const loop::LoopDetectorOptions& options = {}, int max_features = 500);

/// {"recall_at_100_precision", "precision", "recall", "auc"}, each {"tol<k>": value}, and
/// "loop_queries", "accepted", timing means and p95s, "vocabulary_words".
nlohmann::json scoreJson(const DetectorRun& run, const LoopGroundTruth& truth, const std::vector<int64_t>& tolerances);

double meanOf(const std::vector<double>& v);
/// q-quantile (nearest rank), 0 for an empty vector.
double quantileOf(std::vector<double> v, double q);

}  // namespace rmap::bench
