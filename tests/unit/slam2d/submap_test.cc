#include "slam2d/submap.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "slam2d/loop_closure.h"

namespace rmap::slam2d {
namespace {

/// An axis-aligned wall segment from (x0, y0) to (x1, y1) (x0 == x1 or y0 == y1).
struct Wall {
  double x0, y0, x1, y1;
};

/// A 360-beam scan from `robot` against `walls`, exact ranges up to 30 m
/// (beyond: no return), as a keyframe at `robot` (identity mount).
Keyframe scanKeyframe(const std::vector<Wall>& walls, const Pose2& robot) {
  constexpr double kRangeMax = 30.0;
  Keyframe kf;
  kf.pose = robot;
  kf.range_max_m = static_cast<float>(kRangeMax);
  const Pose2 to_robot = robot.inverse();
  for (int b = 0; b < 360; ++b) {
    const double a = robot.theta_rad + 2.0 * std::numbers::pi * b / 360.0;
    const Eigen::Vector2d o = robot.translation(), d(std::cos(a), std::sin(a));
    double t_min = kRangeMax;
    for (const Wall& w : walls) {
      const bool vertical = w.x0 == w.x1;
      const double along = vertical ? d.x() : d.y();
      if (std::abs(along) < 1e-12) continue;
      const double t = ((vertical ? w.x0 : w.y0) - (vertical ? o.x() : o.y())) / along;
      const Eigen::Vector2d hit = o + t * d;
      const double s = vertical ? hit.y() : hit.x();
      const double lo = vertical ? std::min(w.y0, w.y1) : std::min(w.x0, w.x1);
      const double hi = vertical ? std::max(w.y0, w.y1) : std::max(w.x0, w.x1);
      if (t > 1e-6 && t < t_min && s >= lo && s <= hi) t_min = t;
    }
    if (t_min >= kRangeMax) continue;
    const Eigen::Vector2d end = to_robot * (o + t_min * d);
    kf.ends_robot.push_back(end.cast<float>());
    if (kf.match_points.empty() || (end - kf.match_points.back()).norm() >= 0.1) kf.match_points.push_back(end);
  }
  return kf;
}

/// Keyframes every 0.5 m along y = 0 from x = −1.5 to 1.5, a query scan from
/// `truth`, matched from a guess 0.2 m and 0.05 rad off in the loop closer's
/// settings.
std::optional<SubmapMatch> matchIn(const std::vector<Wall>& walls, const Pose2& truth) {
  std::vector<Keyframe> keyframes;
  for (double x = -1.5; x <= 1.5 + 1e-9; x += 0.5) keyframes.push_back(scanKeyframe(walls, Pose2{x, 0.0, 0.0}));
  std::vector<const Keyframe*> members;
  for (const Keyframe& k : keyframes) members.push_back(&k);
  const Pose2 anchor = keyframes[keyframes.size() / 2].pose;
  const SubmapMatcher matcher(members, anchor, LoopClosureOptions{}.submap);
  const Keyframe query = scanKeyframe(walls, truth);
  const Pose2 guess = between(anchor, truth) * Pose2{0.2, -0.15, 0.05};
  return matcher.match(query.match_points, guess, 1.0, 0.3, 0.5);
}

TEST(SubmapMatcher, ACorridorMatchIsAmbiguousAlongItsAxis) {
  // Two walls 2 m apart, longer than the laser reaches: nothing fixes x.
  const std::vector<Wall> corridor{{-60.0, -1.0, 60.0, -1.0}, {-60.0, 1.0, 60.0, 1.0}};
  const std::optional<SubmapMatch> m = matchIn(corridor, Pose2{0.3, 0.1, 0.02});
  ASSERT_TRUE(m) << "the walls match: the scan fits";
  EXPECT_GT(m->score, 0.5);
  EXPECT_NEAR(m->pose.y_m, 0.1, 0.05) << "across the corridor the match is fixed";
  EXPECT_TRUE(m->ambiguous());
  EXPECT_GT(m->rival_score, m->score - LoopClosureOptions{}.submap.ambiguity_margin);
  // The rival lies along the corridor (anchor frame: the corridor runs along x), beyond the excluded radius.
  const Eigen::Vector2d to_rival = m->rival_m - m->pose.translation();
  EXPECT_GE(to_rival.norm(), LoopClosureOptions{}.submap.ambiguity_radius_m - 1e-9);
  EXPECT_LT(std::abs(to_rival.y()), 0.1 * std::abs(to_rival.x()));
}

TEST(SubmapMatcher, ARoomWithAStubWallIsNotAmbiguous) {
  // The same stretch closed by end walls, with a stub wall that breaks the symmetry.
  const std::vector<Wall> room{{-4.0, -1.0, 4.0, -1.0}, {-4.0, 1.0, 4.0, 1.0}, {-4.0, -1.0, -4.0, 1.0},
                               {4.0, -1.0, 4.0, 1.0},   {1.2, 1.0, 1.2, 0.4}};
  const Pose2 truth{0.3, 0.1, 0.02};
  const std::optional<SubmapMatch> m = matchIn(room, truth);
  ASSERT_TRUE(m);
  EXPECT_FALSE(m->ambiguous()) << "runner-up " << m->rival_score << " vs " << m->score;
  EXPECT_NEAR(m->pose.x_m, truth.x_m, 0.05);
  EXPECT_NEAR(m->pose.y_m, truth.y_m, 0.05);
}

TEST(SubmapMatcher, NoAmbiguityCheckWithoutMargin) {
  const std::vector<Wall> corridor{{-60.0, -1.0, 60.0, -1.0}, {-60.0, 1.0, 60.0, 1.0}};
  std::vector<Keyframe> keyframes{scanKeyframe(corridor, Pose2{}), scanKeyframe(corridor, Pose2{0.5, 0.0, 0.0})};
  std::vector<const Keyframe*> members{&keyframes[0], &keyframes[1]};
  SubmapMatcherOptions options = LoopClosureOptions{}.submap;
  options.ambiguity_margin = 0.0;
  const SubmapMatcher matcher(members, Pose2{}, options);
  const std::optional<SubmapMatch> m = matcher.match(keyframes[1].match_points, Pose2{0.4, 0.05, 0.0}, 0.5, 0.1, 0.5);
  ASSERT_TRUE(m);
  EXPECT_FALSE(m->ambiguous());
}

}  // namespace
}  // namespace rmap::slam2d
