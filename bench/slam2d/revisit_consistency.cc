#include "slam2d/revisit_consistency.h"

#include <Eigen/Core>
#include <algorithm>
#include <boost/geometry.hpp>
#include <boost/geometry/index/rtree.hpp>
#include <cmath>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <utility>

namespace rmap::bench {
namespace {

namespace bg = boost::geometry;
namespace bgi = boost::geometry::index;
using BgPoint = bg::model::point<double, 2, bg::cs::cartesian>;
using slam2d::Pose2;

using ScanPair = std::pair<size_t, size_t>;  // earlier, later scan index

double effectiveMaxRange(const slam2d::LaserScan& scan, double max_range_m) {
  return scan.range_max_m > 0.0f ? std::min<double>(scan.range_max_m, max_range_m) : max_range_m;
}

/// Endpoints of the returns within the scan's limits and max_range_m, in its sensor frame.
std::vector<Eigen::Vector2d> endpoints2d(const slam2d::LaserScan& scan, double max_range_m) {
  std::vector<Eigen::Vector2d> points;
  const double range_max_m = effectiveMaxRange(scan, max_range_m);
  for (size_t i = 0; i < scan.ranges_m.size() && i < scan.angles_rad.size(); ++i) {
    const double r = scan.ranges_m[i], a = scan.angles_rad[i];
    if (!std::isfinite(r) || !std::isfinite(a) || r < scan.range_min_m || r >= range_max_m) continue;
    points.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  return points;
}

/// Revisits by one trajectory's poses: earlier index first, sorted.
void addRevisits(const std::vector<Pose2>& poses, const RevisitConsistencyOptions& options,
                 std::vector<ScanPair>& pairs) {
  using Entry = std::pair<BgPoint, size_t>;
  std::vector<Entry> entries;
  for (size_t i = 0; i < poses.size(); ++i)
    if (poses[i].isFinite()) entries.push_back({BgPoint(poses[i].x_m, poses[i].y_m), i});
  const bgi::rtree<Entry, bgi::quadratic<16>> tree(entries);
  const double r = options.max_distance_m;
  std::vector<Entry> near;
  for (const auto& [p, i] : entries) {
    near.clear();
    const bg::model::box<BgPoint> box(BgPoint(p.get<0>() - r, p.get<1>() - r), BgPoint(p.get<0>() + r, p.get<1>() + r));
    tree.query(bgi::within(box), std::back_inserter(near));
    for (const auto& [q, j] : near) {
      if (j < i + options.min_scan_gap) continue;
      if ((poses[j].translation() - poses[i].translation()).norm() > r) continue;
      if (std::abs(slam2d::normalizeAngle(poses[j].theta_rad - poses[i].theta_rad)) > options.max_heading_rad) continue;
      pairs.emplace_back(i, j);
    }
  }
}

/// The earlier scan of a revisit: its endpoints for nearest-neighbour queries and its beams
/// (sorted by angle) to tell which points of the later scan it could have seen.
struct EarlierScan {
  using Endpoint = std::pair<BgPoint, size_t>;  // the point, its index in beam order
  bgi::rtree<Endpoint, bgi::quadratic<16>> endpoints;
  std::vector<std::pair<double, double>> beams;  // angle (rad), range (m; NaN: no return)
  double beam_gap_rad = 0.0;                     // the largest angle between neighbouring beams

  EarlierScan(const slam2d::LaserScan& scan, double max_range_m) {
    std::vector<Endpoint> points;
    for (const Eigen::Vector2d& p : endpoints2d(scan, max_range_m))
      points.push_back({BgPoint(p.x(), p.y()), points.size()});
    endpoints = bgi::rtree<Endpoint, bgi::quadratic<16>>(points);
    for (size_t i = 0; i < scan.ranges_m.size() && i < scan.angles_rad.size(); ++i) {
      if (!std::isfinite(scan.angles_rad[i])) continue;
      const double r = scan.ranges_m[i];
      const bool hit = std::isfinite(r) && r >= scan.range_min_m && r < effectiveMaxRange(scan, max_range_m);
      beams.emplace_back(scan.angles_rad[i], hit ? r : std::nan(""));
    }
    std::sort(beams.begin(), beams.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (size_t i = 1; i < beams.size(); ++i)
      beam_gap_rad = std::max(beam_gap_rad, beams[i].first - beams[i - 1].first);
  }

  /// Whether a point (in this scan's sensor frame) lay where this scan looked: within a beam's
  /// angle and no farther than truncation_m behind the surface that beam hit.
  bool sees(const Eigen::Vector2d& p, double truncation_m) const {
    if (beams.empty()) return false;
    const double bearing = std::atan2(p.y(), p.x());
    auto it =
        std::lower_bound(beams.begin(), beams.end(), bearing, [](const auto& b, double a) { return b.first < a; });
    if (it == beams.end() || (it != beams.begin() && bearing - std::prev(it)->first < it->first - bearing)) --it;
    if (std::abs(it->first - bearing) > beam_gap_rad) return false;
    return std::isfinite(it->second) && p.norm() <= it->second + truncation_m;
  }

  /// Distance (m) to the surface the scan drew, at most truncation_m: to the segment between the
  /// two nearest endpoints when they are neighbours in beam order less than truncation_m apart
  /// (a wall between two beams), else to the nearest endpoint. Point-to-point alone leaves a
  /// floor of about half the beam spacing at range even between perfectly placed scans.
  double distance(const Eigen::Vector2d& p, double truncation_m) const {
    std::vector<Endpoint> nearest;
    endpoints.query(bgi::nearest(BgPoint(p.x(), p.y()), 2), std::back_inserter(nearest));
    if (nearest.empty()) return truncation_m;
    const auto vec = [](const BgPoint& q) { return Eigen::Vector2d(q.get<0>(), q.get<1>()); };
    std::sort(nearest.begin(), nearest.end(), [&](const Endpoint& a, const Endpoint& b) {
      return (vec(a.first) - p).squaredNorm() < (vec(b.first) - p).squaredNorm();
    });
    double d = (vec(nearest[0].first) - p).norm();
    if (nearest.size() == 2 &&
        (nearest[0].second == nearest[1].second + 1 || nearest[1].second == nearest[0].second + 1)) {
      const Eigen::Vector2d a = vec(nearest[0].first), b = vec(nearest[1].first), ab = b - a;
      if (ab.norm() < truncation_m) {
        const double u = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
        d = (a + u * ab - p).norm();
      }
    }
    return std::min(truncation_m, d);
  }
};

}  // namespace

RevisitConsistency revisitConsistency(const std::vector<slam2d::LaserScan>& scans,
                                      const std::vector<std::vector<Pose2>>& trajectories,
                                      const RevisitConsistencyOptions& options) {
  if (trajectories.empty()) throw std::invalid_argument("revisitConsistency needs at least one trajectory");
  for (const std::vector<Pose2>& t : trajectories)
    if (t.size() != scans.size())
      throw std::invalid_argument("revisitConsistency: a trajectory's size differs from the scans'");

  std::vector<ScanPair> pairs;
  for (const std::vector<Pose2>& t : trajectories) addRevisits(t, options, pairs);
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  // A pair is scored only where every trajectory has a pose for both scans.
  std::erase_if(pairs, [&](const ScanPair& p) {
    return std::any_of(trajectories.begin(), trajectories.end(),
                       [&](const std::vector<Pose2>& t) { return !t[p.first].isFinite() || !t[p.second].isFinite(); });
  });
  if (options.max_pairs > 0 && pairs.size() > options.max_pairs) {
    std::vector<ScanPair> thinned;
    for (size_t m = 0; m < options.max_pairs; ++m) thinned.push_back(pairs[m * pairs.size() / options.max_pairs]);
    pairs = std::move(thinned);
  }

  RevisitConsistency out;
  std::vector<double> sum_squared(trajectories.size(), 0.0);
  out.lowest.assign(trajectories.size(), 0);
  std::optional<EarlierScan> earlier;
  size_t earlier_index = scans.size();
  std::vector<std::vector<Eigen::Vector2d>> moved(trajectories.size());
  std::vector<double> residual(trajectories.size());
  for (const auto& [i, j] : pairs) {
    if (i != earlier_index) {  // pairs are sorted: each earlier scan is prepared once
      earlier.emplace(scans[i], options.max_range_m);
      earlier_index = i;
    }
    const std::vector<Eigen::Vector2d> later = endpoints2d(scans[j], options.max_range_m);
    for (size_t t = 0; t < trajectories.size(); ++t) {
      const Pose2 motion = slam2d::between(trajectories[t][i], trajectories[t][j]);
      moved[t].clear();
      for (const Eigen::Vector2d& p : later) moved[t].push_back(motion * p);
    }
    // A point counts for every trajectory when the earlier scan could have seen it under any of
    // them: a trajectory cannot leave out the points it misplaces.
    std::fill(residual.begin(), residual.end(), 0.0);
    size_t counted = 0;
    for (size_t k = 0; k < later.size(); ++k) {
      if (std::none_of(moved.begin(), moved.end(),
                       [&](const auto& m) { return earlier->sees(m[k], options.truncation_m); }))
        continue;
      ++counted;
      for (size_t t = 0; t < trajectories.size(); ++t)
        residual[t] += std::pow(earlier->distance(moved[t][k], options.truncation_m), 2);
    }
    if (counted == 0) continue;  // the two visits saw nothing in common
    ++out.pairs;
    RevisitConsistency::Revisit& revisit = out.revisits.emplace_back(RevisitConsistency::Revisit{i, j, counted, {}});
    for (size_t t = 0; t < trajectories.size(); ++t) {
      sum_squared[t] += residual[t] / double(counted);
      revisit.residual_m.push_back(std::sqrt(residual[t] / double(counted)));
    }
    ++out.lowest[size_t(std::min_element(residual.begin(), residual.end()) - residual.begin())];
  }
  for (double s : sum_squared)
    out.residual_m.push_back(out.pairs == 0 ? std::nan("") : std::sqrt(s / double(out.pairs)));
  return out;
}
}  // namespace rmap::bench
