#include "slam2d/relation_chain.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace rmap::bench {
namespace {

using slam2d::Pose2;

constexpr double kRad_per_deg = std::numbers::pi / 180.0;

/// `n` laser poses `step_m` apart, turning 7° each; the estimate is the truth
/// turned by 10° about the scan `bend` on (a heading jump the relations must see through).
struct BentRun {
  std::vector<int64_t> stamps_ns;
  std::vector<Pose2> truth, estimate;
  BentRun(size_t n, size_t bend, double step_m = 0.1) {
    for (size_t i = 0; i < n; ++i) {
      stamps_ns.push_back(5000 + int64_t(i));
      truth.push_back({step_m * double(i), 0.0, 7.0 * kRad_per_deg * double(i)});
      estimate.push_back(i < bend ? truth.back() : truth[bend] * Pose2{0.0, 0.0, 10.0 * kRad_per_deg} *
                                                       between(truth[bend], truth.back()));
    }
  }
  datasets::SlamRelation relation(size_t from, size_t to) const {
    return {stamps_ns[from], stamps_ns[to], between(truth[from], truth[to]), 0};
  }
};

void expectSameMotion(const Pose2& a, const Pose2& b) {
  EXPECT_NEAR(a.x_m, b.x_m, 1e-9);
  EXPECT_NEAR(a.y_m, b.y_m, 1e-9);
  EXPECT_NEAR(a.theta_rad, b.theta_rad, 1e-9);
}

TEST(RelationChain, ChainsTheRelationsThroughWhereTheEstimateIsBent) {
  const BentRun run(10, 5);
  std::vector<datasets::SlamRelation> relations;
  for (size_t i = 0; i + 1 < 10; ++i) relations.push_back(run.relation(i, i + 1));
  const RelationChain chain(relations, run.stamps_ns);
  ASSERT_FALSE(chain.empty());
  const std::optional<RelationChain::Chained> m = chain.motion(2, 8, run.estimate);
  ASSERT_TRUE(m.has_value());
  expectSameMotion(m->motion, between(run.truth[2], run.truth[8]));
  EXPECT_EQ(m->relations, 6u);
  EXPECT_EQ(m->bridge_scans, 0u);
  EXPECT_GT(std::abs(between(run.estimate[2], run.estimate[8]).theta_rad - m->motion.theta_rad), 9.0 * kRad_per_deg);
  // Backwards: the inverse motion.
  expectSameMotion(chain.motion(8, 2, run.estimate)->motion, between(run.truth[8], run.truth[2]));
}

TEST(RelationChain, TheEstimateBridgesToTheNearestHeldScansAndTheFewestRelationsChain) {
  const BentRun run(10, 5);
  std::vector<datasets::SlamRelation> relations = {run.relation(0, 3), run.relation(3, 6), run.relation(6, 9)};
  RelationChain chain(relations, run.stamps_ns);
  // Scan 1 bridges to 0, scan 8 to 9; the bend lies between the held scans.
  std::optional<RelationChain::Chained> m = chain.motion(1, 8, run.estimate);
  ASSERT_TRUE(m.has_value());
  expectSameMotion(m->motion, between(run.truth[1], run.truth[8]));
  EXPECT_EQ(m->relations, 3u);
  EXPECT_EQ(m->bridge_scans, 2u);
  EXPECT_NEAR(m->bridge_m, 0.2, 1e-9);

  relations.push_back(run.relation(9, 0));
  chain = RelationChain(relations, run.stamps_ns);
  m = chain.motion(1, 8, run.estimate);
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(m->relations, 1u);
  expectSameMotion(m->motion, between(run.truth[1], run.truth[8]));
}

TEST(RelationChain, NothingWithoutAChainOrBeyondTheBridge) {
  const BentRun run(100, 99);
  const RelationChain apart({run.relation(0, 1), run.relation(8, 9)}, run.stamps_ns);
  EXPECT_FALSE(apart.motion(0, 9, run.estimate).has_value()) << "no relation joins the two pairs";
  EXPECT_TRUE(apart.motion(0, 1, run.estimate).has_value());
  // Scans 0.1 m apart: the estimate bridges 1 m, ten scans.
  const RelationChain joined({run.relation(0, 1), run.relation(1, 9)}, run.stamps_ns);
  const std::optional<RelationChain::Chained> m = joined.motion(0, 19, run.estimate);
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(m->bridge_scans, 10u);
  EXPECT_FALSE(joined.motion(0, 20, run.estimate).has_value());
  EXPECT_FALSE(joined.motion(0, 100, run.estimate).has_value()) << "no such scan";
  // Turning on the spot: thirty scans.
  const BentRun spot(100, 99, 0.0);
  const RelationChain on_the_spot({spot.relation(0, 1), spot.relation(1, 9)}, spot.stamps_ns);
  ASSERT_TRUE(on_the_spot.motion(0, 39, spot.estimate).has_value());
  EXPECT_EQ(on_the_spot.motion(0, 39, spot.estimate)->bridge_scans, 30u);
  EXPECT_FALSE(on_the_spot.motion(0, 40, spot.estimate).has_value());
}

TEST(RelationChain, RelationsNamingNoScanOrASharedStampAreLeftOut) {
  BentRun run(10, 5);
  run.stamps_ns[4] = run.stamps_ns[3];  // 3 and 4 share a stamp: it names neither
  datasets::SlamRelation unknown = run.relation(0, 1);
  unknown.to_stamp_ns = 1;
  const RelationChain chain({unknown, run.relation(3, 6)}, run.stamps_ns);
  EXPECT_TRUE(chain.empty());
  EXPECT_FALSE(chain.motion(3, 6, run.estimate).has_value());
}

}  // namespace
}  // namespace rmap::bench
