#pragma once
/// @file closure_ledger.h
/// Which loop closures of the pose graph are reported. A closure is accepted
/// (reported) once an optimisation kept its edge, and withdrawn when a later
/// optimisation disables that edge: later closures showed it wrong, and the
/// map no longer rests on it. No I/O.

#include <cstddef>
#include <functional>
#include <unordered_map>
#include <utility>
#include <vector>

#include "slam2d/pose2.h"

namespace rmap::slam2d {

/// A loop closure between two keyframes (graph node indices).
struct KeyframeClosure {
  size_t query = 0, match = 0;
  double score = 0.0;
  Pose2 relative;  ///< the matched pose of the query in the match's frame (the edge's measurement)
};

class ClosureLedger {
 public:
  /// A closure whose edge entered the graph: the next settle() decides on it.
  void await(size_t edge, const KeyframeClosure& closure);

  struct Settled {
    size_t accepted = 0, withdrawn = 0;
  };
  /// After an optimisation: awaiting closures whose edge is enabled are
  /// accepted, the others dropped unreported; accepted ones whose edge is now
  /// disabled are withdrawn (also when not yet taken: take the accepted ones
  /// first).
  /// @param enabled  whether an edge is still in the graph
  Settled settle(const std::function<bool(size_t)>& enabled);

  /// Closures accepted since the last call, in acceptance order.
  std::vector<KeyframeClosure> takeAccepted();
  /// Closures withdrawn since the last call, each once accepted before.
  std::vector<KeyframeClosure> takeWithdrawn();

 private:
  std::vector<std::pair<size_t, KeyframeClosure>> awaiting_;  ///< edge, closure
  std::unordered_map<size_t, KeyframeClosure> held_;          ///< accepted, edge still enabled
  std::vector<KeyframeClosure> accepted_, withdrawn_;         ///< not yet taken
};

}  // namespace rmap::slam2d
