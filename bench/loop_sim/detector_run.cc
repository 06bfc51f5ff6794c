#include "loop_sim/detector_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <numeric>

namespace rmap::bench {
namespace {

double threadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

std::string tolKey(int64_t k) { return "tol" + std::to_string(k); }

}  // namespace

double meanOf(const std::vector<double>& v) {
  return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

double quantileOf(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const double rank = std::max(1.0, std::ceil(q * static_cast<double>(v.size())));
  const size_t n = std::min(v.size(), static_cast<size_t>(rank)) - 1;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(n), v.end());
  return v[n];
}

DetectorRun runDetector(const std::function<loop::PlaceImage(size_t)>& frame, size_t n, loop::DescriptorType descriptor,
                        const loop::LoopDetectorOptions& options, int max_features) {
  loop::LoopDetector detector(options, loop::makeExtractor(descriptor, max_features));
  DetectorRun run;
  for (size_t i = 0; i < n; ++i) {
    const loop::PlaceImage image = frame(i);
    const double c0 = threadCpuMs();
    const auto t0 = std::chrono::steady_clock::now();
    const loop::FrameResult r = detector.addFrame(image);
    run.wall_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    run.cpu_ms.push_back(threadCpuMs() - c0);
    if (r.best) {
      run.swept.push_back({r.best->query_frame, r.best->reference_frame, r.best->score});
      if (r.accepted) run.accepted.push_back(run.swept.back());
    }
  }
  run.vocabulary_words = detector.vocabularyWords();
  return run;
}

nlohmann::json scoreJson(const DetectorRun& run, const LoopGroundTruth& truth, const std::vector<int64_t>& tolerances) {
  nlohmann::json r100, precision, recall, auc;
  for (int64_t k : tolerances) {
    const PrCurve curve = precisionRecallCurve(run.swept, truth, k);
    const PrPoint at = precisionRecall(run.accepted, truth, k);
    r100[tolKey(k)] = curve.recall_at_100_precision;
    auc[tolKey(k)] = curve.auc;
    precision[tolKey(k)] = at.precision;
    recall[tolKey(k)] = at.recall;
  }
  return {{"loop_queries", truth.size()},
          {"declared_candidates", run.swept.size()},
          {"accepted", run.accepted.size()},
          {"recall_at_100_precision", r100},
          {"precision", precision},  // at the detector's own threshold (accepted loops)
          {"recall", recall},
          {"auc", auc},
          {"ms_per_frame_mean", meanOf(run.wall_ms)},
          {"ms_per_frame_p95", quantileOf(run.wall_ms, 0.95)},
          {"cpu_ms_per_frame_mean", meanOf(run.cpu_ms)},
          {"cpu_ms_per_frame_p95", quantileOf(run.cpu_ms, 0.95)},
          {"vocabulary_words", run.vocabulary_words}};
}

}  // namespace rmap::bench
