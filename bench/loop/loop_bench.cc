#include "loop/loop_bench.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numeric>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "common/machine.h"
#include "loop/loop_scoring.h"
#include "loop/pr_plot.h"

namespace rmap::bench {

using json = nlohmann::json;

std::vector<std::string> listImages(const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw std::runtime_error("not a folder: " + dir);
  std::vector<std::string> out;
  for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (e.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".pgm" || ext == ".ppm" ||
                                ext == ".bmp" || ext == ".tif" || ext == ".tiff")) {
      out.push_back(e.path().string());
    }
  }
  if (out.empty()) throw std::runtime_error("no images in " + dir);
  std::sort(out.begin(), out.end());
  return out;
}

namespace {

double threadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t i = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size() - 1) + 0.5));
  return v[i];
}

double mean(const std::vector<double>& v) {
  return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

std::string tolKey(int64_t k) { return "tol" + std::to_string(k); }

void writeFile(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  if (!out || !(out << text)) throw std::runtime_error("cannot write " + path);
}

json detectorOptionsJson(const LoopBenchOptions& o) {
  const loop::LoopDetectorOptions& d = o.detector;
  return {{"descriptor", o.descriptor},
          {"max_features", o.max_features},
          {"match_distance_fraction", d.vocabulary.match_distance_fraction},
          {"merge_distance_fraction", d.vocabulary.merge_distance_fraction},
          {"tree_branching", d.vocabulary.tree.branching},
          {"tree_leaf_size", d.vocabulary.tree.leaf_size},
          {"tree_count", d.vocabulary.tree.trees},
          {"tree_max_checks", d.vocabulary.tree.max_checks},
          {"track_distance_fraction", d.track_distance_fraction},
          {"purge_after_frames", d.purge_after_frames},
          {"exclusion_window_frames", d.exclusion_window_frames},
          {"island_score_fraction", d.island_score_fraction},
          {"island_gap_frames", d.island_gap_frames},
          {"temporal_consistency_frames", d.temporal_consistency_frames},
          {"verify_islands", d.verify_islands},
          {"verify_per_island", d.verify_per_island},
          {"inlier_floor", d.inlier_floor},
          {"evidence_decay", d.evidence_decay},
          {"min_score", d.min_score}};
}

}  // namespace

int runLoopBench(const LoopBenchOptions& options) {
  if ((options.resize_width > 0) != (options.resize_height > 0)) {
    throw std::runtime_error("--resize needs both width and height");
  }
  const std::vector<std::string> all = listImages(options.images_dir);
  const size_t frames = options.max_frames > 0 ? std::min(options.max_frames, all.size()) : all.size();
  const LoopGroundTruth truth = options.ground_truth.empty()
                                    ? LoopGroundTruth{}
                                    : truncateGroundTruth(readLoopGroundTruth(options.ground_truth),
                                                          static_cast<int64_t>(frames));
  cv::setNumThreads(options.threads);
  loop::LoopDetector detector(options.detector,
                              loop::makeExtractor(loop::descriptorTypeFromString(options.descriptor), options.max_features));

  std::vector<double> wall_ms, cpu_ms;
  std::vector<size_t> words;
  std::vector<loop::FrameResult> results;
  std::vector<LoopDeclaration> swept, accepted;
  cv::Size size;
  for (size_t i = 0; i < frames; ++i) {
    cv::Mat gray = cv::imread(all[i], cv::IMREAD_GRAYSCALE);
    if (gray.empty()) throw std::runtime_error("cannot decode " + all[i]);
    if (options.resize_width > 0) {
      cv::resize(gray, gray, cv::Size(options.resize_width, options.resize_height), 0, 0, cv::INTER_LINEAR);
    }
    size = gray.size();
    const double c0 = threadCpuMs();
    const auto t0 = std::chrono::steady_clock::now();
    loop::FrameResult r = detector.addFrame(gray);
    wall_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    cpu_ms.push_back(threadCpuMs() - c0);
    words.push_back(detector.vocabularyWords());
    if (r.best) {
      swept.push_back({r.best->query_frame, r.best->reference_frame, r.best->score});
      if (r.accepted) accepted.push_back(swept.back());
    }
    results.push_back(std::move(r));
  }

  json j = {{"benchmark", "loop"},
            {"images", options.images_dir},
            {"ground_truth_file", options.ground_truth},
            {"frames", frames},
            {"image_size", {size.width, size.height}},
            {"loop_queries", truth.size()},
            {"declared_candidates", swept.size()},
            {"accepted", accepted.size()},
            {"ms_per_frame_mean", mean(wall_ms)},
            {"ms_per_frame_p95", percentile(wall_ms, 0.95)},
            {"ms_per_frame_max", percentile(wall_ms, 1.0)},
            // wall time suffers from other processes on a shared machine; thread CPU time much less
            {"cpu_ms_per_frame_mean", mean(cpu_ms)},
            {"cpu_ms_per_frame_p95", percentile(cpu_ms, 0.95)},
            {"vocabulary_words", detector.vocabularyWords()},
            {"opencv_threads", options.threads},
            {"detector", detectorOptionsJson(options)},
            {"machine", machineJson()}};
  std::vector<PrCurve> curves;
  if (!truth.empty()) {
    json r100, precision, recall, auc;
    for (int64_t k : options.tolerances) {
      curves.push_back(precisionRecallCurve(swept, truth, k));
      const PrPoint at = precisionRecall(accepted, truth, k);
      r100[tolKey(k)] = curves.back().recall_at_100_precision;
      auc[tolKey(k)] = curves.back().auc;
      precision[tolKey(k)] = at.precision;
      recall[tolKey(k)] = at.recall;
    }
    j["recall_at_100_precision"] = r100;
    j["precision"] = precision;  // at the detector's own threshold (accepted loops)
    j["recall"] = recall;
    j["auc"] = auc;
  }

  std::printf("%zu frames %dx%d, %zu loop queries, %zu candidates, %zu accepted; %zu words\n", frames, size.width,
              size.height, truth.size(), swept.size(), accepted.size(), detector.vocabularyWords());
  for (const PrCurve& c : curves) {
    const PrPoint at = precisionRecall(accepted, truth, c.tolerance);
    std::printf("k=%-3lld recall@100%%P %6.2f %%  AUC %.3f   accepted: precision %6.2f %% recall %6.2f %%\n",
                static_cast<long long>(c.tolerance), 100.0 * c.recall_at_100_precision, c.auc, 100.0 * at.precision,
                100.0 * at.recall);
  }
  std::printf("ms/frame: mean %.2f p95 %.2f (thread CPU: mean %.2f p95 %.2f), OpenCV threads %d\n", mean(wall_ms),
              percentile(wall_ms, 0.95), mean(cpu_ms), percentile(cpu_ms, 0.95), options.threads);

  if (!options.csv_prefix.empty()) {
    for (const PrCurve& c : curves) {
      std::string csv = "threshold,precision,recall,declared,correct\n";
      char line[160];
      for (const PrPoint& p : c.points) {
        std::snprintf(line, sizeof line, "%.6g,%.6f,%.6f,%zu,%zu\n", p.threshold, p.precision, p.recall, p.declared,
                      p.correct);
        csv += line;
      }
      writeFile(options.csv_prefix + "_pr_" + tolKey(c.tolerance) + ".csv", csv);
    }
    std::string csv = "frame,ms,cpu_ms,vocabulary_words,reference,score,accepted\n";
    char line[160];
    for (size_t i = 0; i < frames; ++i) {
      const loop::FrameResult& r = results[i];
      std::snprintf(line, sizeof line, "%zu,%.4f,%.4f,%zu,%lld,%.6g,%d\n", i, wall_ms[i], cpu_ms[i], words[i],
                    static_cast<long long>(r.best ? r.best->reference_frame : -1), r.best ? r.best->score : 0.0,
                    r.accepted ? 1 : 0);
      csv += line;
    }
    writeFile(options.csv_prefix + "_frames.csv", csv);
    if (!curves.empty()) {
      const std::string png = options.csv_prefix + "_pr.png";
      const std::string title = std::filesystem::path(options.images_dir).parent_path().filename().string() + " / " +
                                options.descriptor + ", " + std::to_string(frames) + " frames";
      if (!cv::imwrite(png, drawPrCurves(curves, title))) throw std::runtime_error("cannot write " + png);
    }
    std::cout << "wrote " << options.csv_prefix << "_*.csv" << (curves.empty() ? "" : ", _pr.png") << std::endl;
  }
  if (!options.json_out.empty()) {
    writeFile(options.json_out, j.dump(2) + "\n");
    std::cout << "wrote " << options.json_out << std::endl;
  }
  return 0;
}

}  // namespace rmap::bench
