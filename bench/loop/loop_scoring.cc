#include "loop/loop_scoring.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rmap::bench {

LoopGroundTruth parseLoopGroundTruth(std::istream& in) {
  LoopGroundTruth truth;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (const size_t hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream fields(line);
    int64_t q = 0, r = 0;
    std::string rest;
    if (!(fields >> q)) {
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      throw std::runtime_error("ground truth line " + std::to_string(number) + ": expected 'query reference'");
    }
    if (!(fields >> r) || (fields >> rest)) {
      throw std::runtime_error("ground truth line " + std::to_string(number) + ": expected 'query reference'");
    }
    if (q < 0 || r < 0) throw std::runtime_error("ground truth line " + std::to_string(number) + ": negative index");
    truth[q].insert(r);
  }
  return truth;
}

LoopGroundTruth readLoopGroundTruth(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read ground truth " + path);
  try {
    return parseLoopGroundTruth(in);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

LoopGroundTruth truncateGroundTruth(const LoopGroundTruth& truth, int64_t frames) {
  return {truth.begin(), truth.lower_bound(frames)};
}

bool isCorrect(const LoopGroundTruth& truth, int64_t query, int64_t reference, int64_t tolerance) {
  const auto it = truth.find(query);
  if (it == truth.end()) return false;
  const auto near = it->second.lower_bound(reference - tolerance);
  return near != it->second.end() && *near <= reference + tolerance;
}

namespace {

/// The highest-scoring declaration of each query, surest first.
std::vector<LoopDeclaration> bestPerQuery(const std::vector<LoopDeclaration>& declarations) {
  std::map<int64_t, LoopDeclaration> best;
  for (const LoopDeclaration& d : declarations) {
    auto [it, inserted] = best.emplace(d.query, d);
    if (!inserted && d.score > it->second.score) it->second = d;
  }
  std::vector<LoopDeclaration> out;
  for (const auto& [q, d] : best) out.push_back(d);
  std::stable_sort(out.begin(), out.end(), [](const LoopDeclaration& a, const LoopDeclaration& b) {
    return a.score > b.score;
  });
  return out;
}

}  // namespace

PrCurve precisionRecallCurve(const std::vector<LoopDeclaration>& declarations, const LoopGroundTruth& truth,
                             int64_t tolerance) {
  PrCurve curve;
  curve.tolerance = tolerance;
  curve.loop_queries = truth.size();
  const std::vector<LoopDeclaration> sorted = bestPerQuery(declarations);
  size_t correct = 0;
  for (size_t i = 0; i < sorted.size(); ++i) {
    if (isCorrect(truth, sorted[i].query, sorted[i].reference, tolerance)) ++correct;
    if (i + 1 < sorted.size() && sorted[i + 1].score == sorted[i].score) continue;  // one point per threshold
    PrPoint p;
    p.threshold = sorted[i].score;
    p.declared = i + 1;
    p.correct = correct;
    p.precision = static_cast<double>(correct) / static_cast<double>(p.declared);
    p.recall = curve.loop_queries > 0 ? static_cast<double>(correct) / static_cast<double>(curve.loop_queries) : 0.0;
    curve.points.push_back(p);
  }
  double previous_recall = 0.0;
  for (const PrPoint& p : curve.points) {
    if (p.precision == 1.0) curve.recall_at_100_precision = std::max(curve.recall_at_100_precision, p.recall);
    curve.auc += (p.recall - previous_recall) * p.precision;
    previous_recall = p.recall;
  }
  return curve;
}

PrPoint precisionRecall(const std::vector<LoopDeclaration>& declarations, const LoopGroundTruth& truth,
                        int64_t tolerance) {
  PrPoint p;
  const std::vector<LoopDeclaration> best = bestPerQuery(declarations);
  p.declared = best.size();
  for (const LoopDeclaration& d : best) p.correct += isCorrect(truth, d.query, d.reference, tolerance) ? 1 : 0;
  p.precision = p.declared > 0 ? static_cast<double>(p.correct) / static_cast<double>(p.declared) : 1.0;
  p.recall = truth.empty() ? 0.0 : static_cast<double>(p.correct) / static_cast<double>(truth.size());
  p.threshold = best.empty() ? 0.0 : best.back().score;
  return p;
}

}  // namespace rmap::bench
