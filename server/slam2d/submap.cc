#include "slam2d/submap.h"

#include <cmath>
#include <stdexcept>

#include "slam2d/probability_raster.h"

namespace rmap::slam2d {

SubmapMatcher::SubmapMatcher(std::span<const Keyframe* const> keyframes, const Pose2& anchor_pose,
                             const SubmapMatcherOptions& options)
    : options_(options), grid_(options.resolution_m, options.levels) {
  const Pose2 to_anchor = anchor_pose.inverse();
  for (const Keyframe* k : keyframes) insertKeyframe(grid_, *k, to_anchor * k->pose, nullptr, options_.occupancy);
  if (grid_.empty()) throw std::invalid_argument("SubmapMatcher: the keyframes observe no cell");
  correlative_.emplace(maxFiltered(rasterFromGrid(grid_.level(0), grid_.knownCells(), options_.unknown_probability),
                                   options_.raster_dilation_cells),
                       options_.correlative);
  options_.refinement.search_rad = 0.0;
  options_.refinement.search_m = 0.0;
}

std::optional<SubmapMatch> SubmapMatcher::match(std::span<const Eigen::Vector2d> points, const Pose2& center,
                                                double window_m, double window_rad, double min_score) const {
  const std::optional<CorrelativeMatch> found = correlative_->match(points, center, window_m, window_rad, min_score);
  if (!found) return std::nullopt;
  std::vector<MatchPoint> match_points;
  match_points.reserve(points.size());
  for (const Eigen::Vector2d& p : points) match_points.push_back({p});
  SubmapMatch result;
  result.score = found->score;
  result.refinement = matchScan(grid_, match_points, found->pose, std::nullopt, options_.refinement);
  result.pose = result.refinement.pose;
  const Pose2 shift = between(found->pose, result.pose);
  if (shift.translation().norm() > options_.max_refinement_shift_m ||
      std::abs(shift.theta_rad) > options_.max_refinement_shift_rad)
    return std::nullopt;
  if (options_.ambiguity_margin > 0.0) {
    const double floor = found->score - options_.ambiguity_margin;
    const std::optional<CorrelativeMatch> rival = correlative_->firstAtLeast(
        points, found->pose, options_.ambiguity_window_m, options_.ambiguity_window_rad, std::max(0.0, floor),
        ExcludedDisk{found->pose.translation(), options_.ambiguity_radius_m});
    if (rival) {
      result.rival_score = rival->score;
      result.rival_m = rival->pose.translation();
    }
  }
  return result;
}

}  // namespace rmap::slam2d
