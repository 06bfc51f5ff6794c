#include "slam2d/closure_judge.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

namespace rmap::bench {

using json = nlohmann::json;
using slam2d::Pose2;

std::optional<Pose2> ClosureJudge::referenceOf(std::optional<size_t> input, const std::vector<Pose2>& laser_poses) const {
  if (!input) return std::nullopt;
  const size_t i = *input;
  for (size_t d = 0; d <= kMaxBorrow; ++d) {
    for (const size_t j : {i - d, i + d}) {
      if (j >= reference.size() || j >= laser_poses.size() || !reference[j]) continue;  // i − d wraps to a huge index
      return *reference[j] * between(laser_poses[j], laser_poses[i]);
    }
  }
  return std::nullopt;
}

std::unordered_map<int64_t, size_t> uniqueStampIndex(const std::vector<int64_t>& stamps_ns) {
  std::unordered_map<int64_t, size_t> index;
  constexpr size_t kShared = std::numeric_limits<size_t>::max();
  for (size_t i = 0; i < stamps_ns.size(); ++i) {
    const auto [it, inserted] = index.emplace(stamps_ns[i], i);
    if (!inserted) it->second = kShared;
  }
  std::erase_if(index, [](const auto& entry) { return entry.second == kShared; });
  return index;
}

json judgeClosures(const std::vector<slam2d::LoopClosure2d>& closures,
                   const std::vector<slam2d::LoopClosure2d>& withdrawn, const JudgedRun& run,
                   const std::vector<ClosureJudge>& judges) {
  const auto key = [](const slam2d::LoopClosure2d& c) {
    return std::tie(c.query_trajectory, c.query_stamp_ns, c.match_trajectory, c.match_stamp_ns);
  };
  const auto isWithdrawn = [&](const slam2d::LoopClosure2d& c) {
    return std::any_of(withdrawn.begin(), withdrawn.end(), [&](const slam2d::LoopClosure2d& w) { return key(w) == key(c); });
  };
  const std::unordered_map<int64_t, size_t> index_of_stamp = uniqueStampIndex(run.stamps_ns);
  const auto inputOf = [&](int64_t stamp) -> std::optional<size_t> {
    const auto it = index_of_stamp.find(stamp);
    return it == index_of_stamp.end() ? std::nullopt : std::optional<size_t>(it->second);
  };

  std::vector<size_t> judged(judges.size(), 0), wrong(judges.size(), 0), wrong_withdrawn(judges.size(), 0);
  std::vector<double> worst_m(judges.size(), 0.0);
  size_t cross = 0, judged_by_all = 0, wrong_by_all = 0;
  json list = json::array();
  for (const slam2d::LoopClosure2d& c : closures) {
    cross += c.query_trajectory != c.match_trajectory;
    const std::optional<size_t> query = inputOf(c.query_stamp_ns), match = inputOf(c.match_stamp_ns);
    const Pose2 mount = query ? run.sensor_mounts[*query] : Pose2{};
    const Pose2 measured = mount.inverse() * c.relative * mount;  // laser to laser
    const bool was_withdrawn = isWithdrawn(c);
    json item = {{"query_stamp_ns", c.query_stamp_ns}, {"match_stamp_ns", c.match_stamp_ns}, {"score", c.score},
                 {"relative", {c.relative.x_m, c.relative.y_m, c.relative.theta_rad}}, {"withdrawn", was_withdrawn}};
    json by_judge = json::array();
    size_t judged_here = 0, wrong_here = 0;
    for (size_t j = 0; j < judges.size(); ++j) {
      const std::optional<Pose2> rq = judges[j].referenceOf(query, run.laser_poses);
      const std::optional<Pose2> rm = judges[j].referenceOf(match, run.laser_poses);
      if (!rq || !rm) {
        by_judge.push_back(nullptr);
        continue;
      }
      const Pose2 e = between(between(*rm, *rq), measured);
      const double error_m = e.translation().norm();
      const bool is_wrong = error_m > ClosureJudge::kMaxError_m || std::abs(e.theta_rad) > ClosureJudge::kMaxError_rad;
      ++judged[j];
      ++judged_here;
      wrong[j] += is_wrong;
      wrong_withdrawn[j] += is_wrong && was_withdrawn;
      wrong_here += is_wrong;
      worst_m[j] = std::max(worst_m[j], error_m);
      by_judge.push_back({{"error_m", error_m}, {"error_deg", std::abs(e.theta_rad) * 180.0 / std::numbers::pi},
                          {"false", is_wrong}});
    }
    if (!judges.empty() && !by_judge.front().is_null()) item.update(by_judge.front());
    if (judges.size() > 1) {
      item["by_judge"] = by_judge;
      if (judged_here == judges.size()) {
        ++judged_by_all;
        wrong_by_all += wrong_here == judges.size();
      }
    }
    list.push_back(std::move(item));
  }

  json per_judge = json::array();
  for (size_t j = 0; j < judges.size(); ++j)
    per_judge.push_back({{"judged_by", judges[j].judged_by},
                         {"closures_judged", judged[j]},
                         {"false_closures", wrong[j]},
                         {"false_closures_withdrawn", wrong_withdrawn[j]},
                         {"worst_closure_error_m", judged[j] > 0 ? json(worst_m[j]) : json(nullptr)}});
  const bool first = !judges.empty() && judged.front() > 0;
  const bool several = judges.size() > 1;
  return {{"closures", closures.size()},
          {"withdrawn", std::count_if(closures.begin(), closures.end(), isWithdrawn)},
          {"cross_trajectory_closures", cross},
          {"closures_judged", judges.empty() ? 0 : judged.front()},
          {"false_closures", first ? json(wrong.front()) : json(nullptr)},
          {"false_closures_withdrawn", first ? json(wrong_withdrawn.front()) : json(nullptr)},
          {"worst_closure_error_m", first ? json(worst_m.front()) : json(nullptr)},
          {"judged_by", judges.empty() ? json(nullptr) : json(judges.front().judged_by)},
          {"judges", per_judge},
          {"closures_judged_by_all", several ? json(judged_by_all) : json(nullptr)},
          {"false_by_all_judges", several ? json(wrong_by_all) : json(nullptr)},
          {"list", list}};
}

}  // namespace rmap::bench
