#include "slam2d/relation_chain.h"

#include <deque>
#include <limits>
#include <unordered_map>

#include "slam2d/closure_judge.h"

namespace rmap::bench {

using slam2d::Pose2;

RelationChain::RelationChain(const std::vector<datasets::SlamRelation>& relations,
                             const std::vector<int64_t>& stamps_ns)
    : next_(stamps_ns.size()) {
  const std::unordered_map<int64_t, size_t> index_of_stamp = uniqueStampIndex(stamps_ns);
  for (const datasets::SlamRelation& r : relations) {
    const auto a = index_of_stamp.find(r.from_stamp_ns), b = index_of_stamp.find(r.to_stamp_ns);
    if (a == index_of_stamp.end() || b == index_of_stamp.end() || a->second == b->second) continue;
    next_[a->second].emplace_back(b->second, r.motion);
    next_[b->second].emplace_back(a->second, r.motion.inverse());
    ++relation_count_;
  }
}

std::optional<RelationChain::Bridge> RelationChain::nearestHeld(size_t scan,
                                                                 const std::vector<Pose2>& laser_poses) const {
  std::optional<Bridge> nearest;
  for (const ptrdiff_t step : {-1, 1}) {  // the first held scan each way, then the nearer of the two
    double path_m = 0.0;
    for (size_t d = 0; d <= kMaxBridgeScans; ++d) {
      const ptrdiff_t j = static_cast<ptrdiff_t>(scan) + step * static_cast<ptrdiff_t>(d);
      if (j < 0 || static_cast<size_t>(j) >= next_.size()) break;
      if (d > 0) path_m += (laser_poses[size_t(j)].translation() - laser_poses[size_t(j - step)].translation()).norm();
      if (path_m > kMaxBridge_m) break;
      if (next_[size_t(j)].empty()) continue;
      if (!nearest || path_m < nearest->path_m) nearest = Bridge{size_t(j), path_m, d};
      break;
    }
  }
  return nearest;
}

std::optional<RelationChain::Chained> RelationChain::motion(size_t from, size_t to,
                                                            const std::vector<Pose2>& laser_poses) const {
  if (from >= next_.size() || to >= next_.size() || laser_poses.size() < next_.size()) return std::nullopt;
  const std::optional<Bridge> from_bridge = nearestHeld(from, laser_poses), to_bridge = nearestHeld(to, laser_poses);
  if (!from_bridge || !to_bridge) return std::nullopt;
  const size_t start = from_bridge->scan, goal = to_bridge->scan;
  // Breadth first: each relation adds its own error, so the fewest of them.
  constexpr size_t kUnseen = std::numeric_limits<size_t>::max();
  std::vector<size_t> came_from(next_.size(), kUnseen);
  std::vector<Pose2> start_to(next_.size());  // motion from `start` to each scan reached
  came_from[start] = start;
  std::deque<size_t> frontier = {start};
  while (!frontier.empty() && came_from[goal] == kUnseen) {
    const size_t u = frontier.front();
    frontier.pop_front();
    for (const auto& [v, motion] : next_[u]) {
      if (came_from[v] != kUnseen) continue;
      came_from[v] = u;
      start_to[v] = start_to[u] * motion;
      frontier.push_back(v);
    }
  }
  if (came_from[goal] == kUnseen) return std::nullopt;
  size_t hops = 0;
  for (size_t v = goal; v != start; v = came_from[v]) ++hops;
  return Chained{between(laser_poses[from], laser_poses[start]) * start_to[goal] *
                     between(laser_poses[goal], laser_poses[to]),
                 hops, from_bridge->scans + to_bridge->scans, from_bridge->path_m + to_bridge->path_m};
}

}  // namespace rmap::bench
