#pragma once
/// @file revisit_consistency.h
/// A check of 2D trajectories that needs no reference: where the robot came
/// back to a place, the scans of the two visits must lie on each other under
/// the poses a trajectory gives them. Scoring several trajectories (an
/// estimate and a SLAM-made reference) on the same revisits tells which of
/// them the scans agree with where they disagree with each other. It sees
/// only revisits: the shape of a loop between its ends, which no scan
/// overlaps, is not checked. Pure functions, no I/O.

#include <cstddef>
#include <vector>

#include "slam2d/laser_scan.h"
#include "slam2d/pose2.h"

namespace rmap::bench {

struct RevisitConsistencyOptions {
  /// The two scans of a revisit are at least this many scans apart, so
  /// consecutive scans (which the front end matched to each other) do not count.
  size_t min_scan_gap = 30;
  /// Sensor positions this close (m) and headings this close (rad) in any of
  /// the trajectories make a revisit: a 180° scanner sees little of a place
  /// from behind, and a trajectory that misplaces a revisit by up to this
  /// much is still caught.
  double max_distance_m = 2.0;
  double max_heading_rad = 0.8;
  /// A point farther than this (m) from the other scan's endpoints counts as
  /// this far, so one misplaced point (a person, a door) weighs little. A
  /// point is also left out where it lies more than this behind the surface
  /// the earlier scan saw along its bearing (hidden from that scan).
  double truncation_m = 0.3;
  /// Endpoints beyond this range (m) are left out: their position error grows
  /// with range for any heading error, and far walls are seen thin.
  double max_range_m = 20.0;
  /// More revisits are thinned evenly (every k-th of them in scan order).
  size_t max_pairs = 2000;
};

struct RevisitConsistency {
  size_t pairs = 0;  ///< revisits scored: the earlier scan could see some of the later one's endpoints
  /// Per trajectory: the root mean square over the revisits of each revisit's
  /// residual, the rms distance (m) of the later scan's endpoints to the
  /// nearest endpoint of the earlier scan, truncated as above. Only the
  /// endpoints the earlier scan could have seen count (within its beams'
  /// angles, not hidden behind what they hit), and on a revisit the same for
  /// every trajectory: those it could have seen under any trajectory's
  /// poses, so no trajectory escapes by moving its points out of sight. NaN
  /// without revisits.
  std::vector<double> residual_m;
  /// Per trajectory: revisits where its residual is the lowest of all
  /// trajectories (ties go to the first).
  std::vector<size_t> lowest;
  /// Each revisit scored, in scan order: where the figures above come from.
  struct Revisit {
    size_t earlier = 0, later = 0;    ///< scan indices
    size_t points = 0;                ///< endpoints of the later scan that counted
    std::vector<double> residual_m;   ///< per trajectory, this revisit's rms distance
  };
  std::vector<Revisit> revisits;
};

/// @param scans         the scans in sequence (endpoints in their sensor frames)
/// @param trajectories  one or more trajectories of sensor poses, one pose per scan each
/// @throws std::invalid_argument when no trajectory is given or a size differs from scans
RevisitConsistency revisitConsistency(const std::vector<slam2d::LaserScan>& scans,
                                      const std::vector<std::vector<slam2d::Pose2>>& trajectories,
                                      const RevisitConsistencyOptions& options = {});

}  // namespace rmap::bench
