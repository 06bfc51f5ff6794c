#pragma once
/// @file loop_scoring.h
/// Precision–recall of a loop detector against ground-truth loop pairs, the
/// way the loop-closure literature scores it.
///
/// Ground truth: pairs (q, r) of frames showing the same place (0-based,
/// q > r). A loop query is a frame q with at least one pair. A detector
/// declares at most one loop (q, r) per frame with a score; at threshold t it
/// declares those with score ≥ t. Under tolerance k a declaration is correct
/// if the ground truth holds (q, r') with |r − r'| ≤ k.
///  - precision(t) = correct declarations / declarations (1 when none);
///  - recall(t) = loop queries with a correct declaration / loop queries;
///  - the curve: one point per distinct score, thresholds from high to low;
///  - recall at 100 % precision: the highest recall of a point with
///    precision 1 (0 if the surest declaration is already wrong);
///  - AUC: Σ (recall_i − recall_{i−1}) · precision_i over the curve in
///    order of rising recall, from recall 0 (average precision).

#include <cstdint>
#include <istream>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace rmap::bench {

/// q → the set of its true references r.
using LoopGroundTruth = std::map<int64_t, std::set<int64_t>>;

/// Reads `query reference` pairs, one per line; `#` starts a comment, blank lines are skipped.
/// @throws std::runtime_error with the line number on a malformed line or a negative index
LoopGroundTruth parseLoopGroundTruth(std::istream& in);
/// @throws std::runtime_error when the file cannot be read or is malformed
LoopGroundTruth readLoopGroundTruth(const std::string& path);
/// Only the pairs whose query is below `frames`.
LoopGroundTruth truncateGroundTruth(const LoopGroundTruth& truth, int64_t frames);

struct LoopDeclaration {
  int64_t query = -1;
  int64_t reference = -1;
  double score = 0.0;
};

/// Whether (query, reference) is a true loop under tolerance k.
bool isCorrect(const LoopGroundTruth& truth, int64_t query, int64_t reference, int64_t tolerance);

struct PrPoint {
  double threshold = 0.0;
  double precision = 1.0;
  double recall = 0.0;
  size_t declared = 0;
  size_t correct = 0;
};

struct PrCurve {
  int64_t tolerance = 0;
  size_t loop_queries = 0;
  std::vector<PrPoint> points;  ///< thresholds falling, recall rising
  double recall_at_100_precision = 0.0;
  double auc = 0.0;
};

/// @param declarations  at most one per query (the detector's best); more per query: the highest score counts
PrCurve precisionRecallCurve(const std::vector<LoopDeclaration>& declarations, const LoopGroundTruth& truth,
                             int64_t tolerance);

/// Precision and recall of one fixed set of declarations (the detector's accepted loops).
PrPoint precisionRecall(const std::vector<LoopDeclaration>& declarations, const LoopGroundTruth& truth,
                        int64_t tolerance);

}  // namespace rmap::bench
