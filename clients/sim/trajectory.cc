#include "sim/trajectory.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>

namespace rmap::sim {
namespace {

/// Positions are kept this far inside their cell so that a point lookup finds
/// the same cell (and voxel column) as the planner did.
constexpr double kInsideCell_m = 1e-6;

/// A straight horizontal piece of the path inside one cell, at one node's sensor height.
struct CellPiece {
  Eigen::Vector2d a, b;
  int node;
};

/// Walks the straight segment between two nodes' cell centres over the cell
/// grid (2D Amanatides & Woo). Succeeds when every cell crossed has a node
/// within max_step of the previous one and the walk ends at node `to`.
bool straightPieces(const NavigableSpace& space, int from, int to, std::vector<CellPiece>& out) {
  const auto& nodes = space.nodes();
  const Eigen::Vector2d p0 = space.sensorPosition(from).head<2>(), p1 = space.sensorPosition(to).head<2>();
  const Eigen::Vector2d d = p1 - p0;
  const Eigen::Vector2d grid_origin = space.cellBox(0, 0).min();
  const double c = space.cellSize();
  int cell[2] = {nodes[from].cx, nodes[from].cy};
  const int last[2] = {nodes[to].cx, nodes[to].cy};
  int step[2];
  double t_max[2], t_delta[2];
  for (int a = 0; a < 2; ++a) {
    step[a] = last[a] > cell[a] ? 1 : (last[a] < cell[a] ? -1 : 0);
    if (step[a] == 0) {
      t_max[a] = t_delta[a] = std::numeric_limits<double>::infinity();
    } else {
      const double face = grid_origin[a] + (cell[a] + (step[a] > 0 ? 1 : 0)) * c;
      t_max[a] = (face - p0[a]) / d[a];
      t_delta[a] = c / std::abs(d[a]);
    }
  }
  const size_t first_piece = out.size();
  int node = from;
  double t = 0.0;
  const int max_cells = std::abs(last[0] - nodes[from].cx) + std::abs(last[1] - nodes[from].cy) + 1;
  for (int visited = 0; visited < max_cells; ++visited) {
    const bool at_end = cell[0] == last[0] && cell[1] == last[1];
    const int a = t_max[0] <= t_max[1] ? 0 : 1;
    const double t_out = at_end ? 1.0 : std::min(t_max[a], 1.0);
    out.push_back({p0 + t * d, p0 + t_out * d, node});
    if (at_end) {
      if (node == to) return true;
      break;
    }
    cell[a] += step[a];
    t = t_out;
    t_max[a] += t_delta[a];
    node = space.nodeNear(cell[0], cell[1], nodes[node].surface_voxel);
    if (node < 0) break;
  }
  out.resize(first_piece);
  return false;
}

/// Shortest paths from the nearest of some source nodes (Dijkstra over the navigable graph).
void shortestPaths(const NavigableSpace& space, const std::vector<int>& sources, std::vector<double>& dist,
                   std::vector<int>& parent) {
  dist.assign(space.size(), std::numeric_limits<double>::infinity());
  parent.assign(space.size(), -1);
  using Entry = std::pair<double, int>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
  for (int source : sources) {
    dist[source] = 0.0;
    open.emplace(0.0, source);
  }
  while (!open.empty()) {
    const auto [d, node] = open.top();
    open.pop();
    if (d > dist[node]) continue;
    space.forEachNeighbour(node, [&](int next, double length) {
      if (d + length < dist[next]) {
        dist[next] = d + length;
        parent[next] = node;
        open.emplace(dist[next], next);
      }
    });
  }
}

/// Produces the tour: legs between goals turned into pieces, and poses placed
/// along the pieces.
class TourPlanner {
 public:
  TourPlanner(const NavigableSpace& space, const TrajectoryOptions& options, uint64_t seed)
      : space_(space), options_(options), rng_(seed), visited_(space.size(), 0) {
    for (size_t i = 0; i < space.size(); ++i) {
      if (space.component(static_cast<int>(i)) == 0) members_.push_back(static_cast<int>(i));
    }
  }

  std::vector<Eigen::Vector3d> positions() {
    int at = members_[std::uniform_int_distribution<size_t>(0, members_.size() - 1)(rng_)];
    Eigen::Vector3d pose = space_.sensorPosition(at);
    std::vector<Eigen::Vector3d> out{pose};
    markVisited(pose);
    // The last pose is kept a hair inside the step so clamping into cells cannot exceed it.
    const double step = options_.step_m - 1e-5;
    size_t piece = 0;
    Eigen::Vector3d start = pose;  // where the unconsumed part of the current piece begins
    while (out.size() < static_cast<size_t>(options_.num_poses)) {
      if (piece == pieces_.size()) {
        pieces_.clear();
        piece = 0;
        at = planLeg(at);
        start = point(pieces_[0], 0.0);
      }
      const CellPiece& p = pieces_[piece];
      const Eigen::Vector3d end = point(p, 1.0);
      if ((end - pose).norm() <= step) {
        // The whole rest of this piece is within reach; look at the next one.
        ++piece;
        if (piece < pieces_.size() && (point(pieces_[piece], 0.0) - pose).norm() > step) {
          emit(end, p, pose, out);  // a step up/down follows: stop at the edge
        }
        if (piece < pieces_.size()) start = point(pieces_[piece], 0.0);
        continue;
      }
      // First point of [start, end] at distance `step` from the pose (start is within it).
      const Eigen::Vector3d seg = end - start, rel = start - pose;
      const double a = seg.squaredNorm(), b = 2.0 * seg.dot(rel), c = rel.squaredNorm() - step * step;
      const double s = std::clamp((-b + std::sqrt(std::max(0.0, b * b - 4.0 * a * c))) / (2.0 * a), 0.0, 1.0);
      start += s * seg;
      emit(start, p, pose, out);
    }
    return out;
  }

 private:
  Eigen::Vector3d point(const CellPiece& p, double u) const {
    const Eigen::Vector2d xy = p.a + u * (p.b - p.a);
    return {xy.x(), xy.y(), space_.sensorZ(p.node)};
  }

  void emit(const Eigen::Vector3d& position, const CellPiece& p, Eigen::Vector3d& pose, std::vector<Eigen::Vector3d>& out) {
    const Eigen::AlignedBox2d box = space_.cellBox(space_.nodes()[p.node].cx, space_.nodes()[p.node].cy);
    const Eigen::Vector2d inset = Eigen::Vector2d::Constant(kInsideCell_m);
    const Eigen::Vector2d xy = position.head<2>().cwiseMax(box.min() + inset).cwiseMin(box.max() - inset);
    pose = Eigen::Vector3d(xy.x(), xy.y(), position.z());
    out.push_back(pose);
    markVisited(pose);
  }

  /// Marks nodes within coverage_radius_m horizontally (and within a metre of height) as visited.
  void markVisited(const Eigen::Vector3d& pose) {
    int cx, cy;
    if (!space_.cellOf(pose.head<2>(), cx, cy)) return;
    const int r = static_cast<int>(std::ceil(options_.coverage_radius_m / space_.cellSize()));
    for (int y = std::max(0, cy - r); y <= std::min(space_.cellsY() - 1, cy + r); ++y) {
      for (int x = std::max(0, cx - r); x <= std::min(space_.cellsX() - 1, cx + r); ++x) {
        if (std::hypot(x - cx, y - cy) > r) continue;
        const auto [first, last] = space_.nodesInCell(x, y);
        for (int n = first; n < last; ++n) {
          if (std::abs(space_.sensorZ(n) - pose.z()) <= 1.0) visited_[n] = 1;
        }
      }
    }
  }

  /// Chooses the next goal from `from`, fills pieces_ with the straightened path, returns the goal.
  /// The goal is the place farthest (by path length) from every visited one:
  /// farthest-point sampling spreads the tour over far-apart parts first.
  int planLeg(int from) {
    std::vector<double> dist;
    std::vector<int> parent;
    std::vector<int> seen;
    for (int n : members_) {
      if (visited_[n]) seen.push_back(n);
    }
    shortestPaths(space_, seen, dist, parent);
    int goal = from;
    for (int n : members_) {
      if (dist[n] > dist[goal]) goal = n;
    }
    const bool all_seen = goal == from;
    if (all_seen) std::fill(visited_.begin(), visited_.end(), 0);  // start a new round from here
    shortestPaths(space_, {from}, dist, parent);
    if (all_seen) {
      for (int n : members_) {
        if (dist[n] > dist[goal]) goal = n;
      }
    }
    std::vector<int> path;
    for (int n = goal; n >= 0; n = parent[n]) path.push_back(n);
    std::reverse(path.begin(), path.end());
    // Straighten: from each kept node, jump to the farthest node still in straight sight.
    for (size_t i = 0; i + 1 < path.size();) {
      std::vector<CellPiece> best;
      size_t j = i + 1;
      if (!straightPieces(space_, path[i], path[j], best)) {
        throw std::logic_error("planTrajectory: neighbouring nodes are not in straight sight");
      }
      std::vector<CellPiece> trial;
      while (j + 1 < path.size() && straightPieces(space_, path[i], path[j + 1], trial)) {
        best.swap(trial);
        trial.clear();
        ++j;
      }
      pieces_.insert(pieces_.end(), best.begin(), best.end());
      i = j;
    }
    return goal;
  }

  const NavigableSpace& space_;
  const TrajectoryOptions& options_;
  std::mt19937_64 rng_;
  std::vector<int> members_;
  std::vector<char> visited_;
  std::vector<CellPiece> pieces_;
};

}  // namespace

void TrajectoryOptions::validate() const {
  NavigableOptions::validate();
  auto fail = [](const std::string& what) { throw std::invalid_argument("TrajectoryOptions: " + what); };
  if (num_poses < 1) fail("num_poses must be ≥ 1");
  if (!(step_m >= max_step_m + 0.01) || !std::isfinite(step_m)) {
    fail("step_m must be finite and ≥ max_step_m + 0.01 (a stair step must fit in one pose step)");
  }
  if (!(coverage_radius_m >= 0.0) || !std::isfinite(coverage_radius_m)) fail("coverage_radius_m must be ≥ 0");
}

std::vector<Eigen::Isometry3d> planTrajectory(const VoxelWorld& world, const TrajectoryOptions& options,
                                              uint64_t seed) {
  options.validate();
  const NavigableSpace space(world, options);
  if (space.size() == 0 || space.componentSize(0) < 2) {
    std::ostringstream msg;
    msg << "planTrajectory: no navigable space: need a surface with " << options.sensor_height_m + options.clearance_m
        << " m of free headroom, " << options.clearance_m << " m of horizontal clearance above "
        << std::min(options.body_bottom_m, options.sensor_height_m - options.clearance_m)
        << " m, fitting inside the grid" << (world.hasKnownFree() ? ", with the sensor in known free space" : "")
        << ", and at least two connected cells of " << space.cellSize() << " m";
    throw std::runtime_error(msg.str());
  }
  const std::vector<Eigen::Vector3d> positions = TourPlanner(space, options, seed).positions();

  // Heading of each move with a horizontal component; other poses inherit
  // the previous heading (the first ones the first heading).
  std::vector<double> yaw(positions.size(), std::numeric_limits<double>::quiet_NaN());
  for (size_t i = 0; i + 1 < positions.size(); ++i) {
    const Eigen::Vector2d move = (positions[i + 1] - positions[i]).head<2>();
    if (move.norm() > 1e-9) yaw[i] = std::atan2(move.y(), move.x());
  }
  const auto first = std::find_if(yaw.begin(), yaw.end(), [](double y) { return !std::isnan(y); });
  double heading = first == yaw.end() ? 0.0 : *first;
  std::vector<Eigen::Isometry3d> poses(positions.size(), Eigen::Isometry3d::Identity());
  for (size_t i = 0; i < positions.size(); ++i) {
    if (!std::isnan(yaw[i])) heading = yaw[i];
    poses[i].translation() = positions[i];
    poses[i].linear() = Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  }
  return poses;
}

}  // namespace rmap::sim
