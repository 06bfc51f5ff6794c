#pragma once
/// @file closure_ledger.h
/// Which loop closures of the pose graph are reported. A closure whose edge
/// the optimisation after it kept is tentative: it is accepted (reported) once
/// a later optimisation keeps it too, or once its trajectory went on for
/// hold_ns of sensor time with the edge still in the graph. A tentative one
/// that a later optimisation disables is dropped unreported: the closures after
/// it showed it wrong before anyone was told. An accepted closure whose edge a
/// later optimisation disables is withdrawn. No I/O.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
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
  /// The matched submap as it was matched against: each keyframe and its pose in the match's frame.
  std::vector<std::pair<size_t, Pose2>> submap;
  /// An ambiguous match (a rival pose scored nearly as well): the unit
  /// direction towards the rival in the match's frame. Along it `relative` is
  /// known only to the ambiguity window, across it as any match.
  std::optional<Eigen::Vector2d> ambiguous_direction{};
};

class ClosureLedger {
 public:
  /// @param hold_ns  sensor time a kept closure waits for a later optimisation
  ///                 before it is accepted anyway (≥ 0; 0: accepted when first kept)
  explicit ClosureLedger(int64_t hold_ns = 0);

  /// A closure whose edge entered the graph: the next settle() decides on it.
  /// @param trajectory  the query keyframe's trajectory, whose sensor time holds it
  void await(size_t edge, const KeyframeClosure& closure, size_t trajectory);

  struct Settled {
    size_t accepted = 0, withdrawn = 0;
    size_t dropped_tentative = 0;  ///< kept by an earlier optimisation, disabled by this one: never reported
  };
  /// After an optimisation: accepted closures whose edge is now disabled are
  /// withdrawn (also when not yet taken: take the accepted ones first);
  /// tentative ones are accepted when their edge is enabled and dropped when
  /// not; awaiting ones whose edge is enabled become tentative from `now_ns`
  /// (accepted at once when hold_ns is 0), the others are dropped.
  /// @param enabled  whether an edge is still in the graph
  /// @param now_ns   a trajectory's newest sensor time
  Settled settle(const std::function<bool(size_t)>& enabled, const std::function<int64_t(size_t)>& now_ns);

  /// Accepts `trajectory`'s tentative closures held since now_ns − hold_ns or earlier.
  /// @return how many were accepted
  size_t confirmHeld(size_t trajectory, int64_t now_ns);
  /// Accepts every tentative closure (the data ended: nothing can contradict them now).
  size_t confirmAll();

  /// Closures accepted since the last call, in acceptance order.
  std::vector<KeyframeClosure> takeAccepted();
  /// Closures withdrawn since the last call, each once accepted before
  /// (without KeyframeClosure::submap: only the accepted report carries it).
  std::vector<KeyframeClosure> takeWithdrawn();

 private:
  struct Entry {
    size_t edge = 0;
    KeyframeClosure closure;
    size_t trajectory = 0;
    int64_t kept_ns = 0;  ///< the trajectory's sensor time when an optimisation first kept it
  };
  void accept(const Entry& entry);

  int64_t hold_ns_;
  std::vector<Entry> awaiting_, tentative_;
  std::unordered_map<size_t, KeyframeClosure> held_;   ///< accepted, edge still enabled
  std::vector<KeyframeClosure> accepted_, withdrawn_;  ///< not yet taken
};

}  // namespace rmap::slam2d
