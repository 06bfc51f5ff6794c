#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "datasets/slam_relations.h"
#include "slam2d/pose2.h"

namespace rmap::bench {

/// The true motion between two scans of a log, chained through its relations
/// (motions between scans checked by hand: what the raw logs' accuracy is
/// measured by). It judges a loop closure without a corrected log, whose own
/// pose of a scan can be degrees off (raw fr079, BENCHMARKS.md §4).
/// The chain takes the fewest relations from the scan nearest the first that
/// a relation holds to the one nearest the second; the estimate bridges each
/// end (a short way: millimetres to centimetres of error).
class RelationChain {
 public:
  /// The estimate bridges at most this many scans, and this far (its path, metres), at each end of a chain.
  static constexpr size_t kMaxBridgeScans = 30;
  static constexpr double kMaxBridge_m = 1.0;

  struct Chained {
    slam2d::Pose2 motion;     ///< laser to laser, from the first scan to the second
    size_t relations = 0;     ///< relations chained
    size_t bridge_scans = 0;  ///< scans bridged by the estimate, both ends together
    double bridge_m = 0.0;    ///< the estimate's path over the bridges, both ends together
  };

  /// @param stamps_ns  per input scan; relations name their scans by stamp,
  ///        and a stamp several scans share names none (uniqueStampIndex)
  RelationChain(const std::vector<datasets::SlamRelation>& relations, const std::vector<int64_t>& stamps_ns);

  /// The motion from scan `from` to scan `to` (input indices).
  /// @param laser_poses  the estimate per input scan, for the bridges
  /// @return none when no relation holds a scan within a bridge of an end
  ///         (kMaxBridgeScans, kMaxBridge_m), or no chain of relations joins the two
  std::optional<Chained> motion(size_t from, size_t to, const std::vector<slam2d::Pose2>& laser_poses) const;

  /// Whether any relation names two scans of the run.
  bool empty() const { return relation_count_ == 0; }

 private:
  struct Bridge {
    size_t scan;      ///< held by a relation
    double path_m;    ///< the estimate's path from the bridged scan to it
    size_t scans;
  };
  /// The scan a relation holds nearest `scan` along the estimate's path, within a bridge.
  std::optional<Bridge> nearestHeld(size_t scan, const std::vector<slam2d::Pose2>& laser_poses) const;

  std::vector<std::vector<std::pair<size_t, slam2d::Pose2>>> next_;  ///< per scan: (other scan, motion to it)
  size_t relation_count_ = 0;
};

}  // namespace rmap::bench
