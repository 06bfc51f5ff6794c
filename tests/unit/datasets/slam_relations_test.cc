#include "datasets/slam_relations.h"

#include <gtest/gtest.h>

#include <numbers>
#include <stdexcept>
#include <string>

#include "dataset_test_support.h"

namespace rmap::datasets {
namespace {

void expectRelationsError(const std::string& text, const std::string& part) {
  expectParseError([](const std::string& c) { parseSlamRelations(c, "r.txt"); }, text, part);
}

TEST(SlamRelations, ParsesStampsAndMotion) {
  const auto r = parseSlamRelations(
      "# t1 t2 x y z roll pitch yaw\n976052905.167303 976052911.885496 -0.056990 -0.128430 0 0 0 -1.682210\n\n"
      "1.5 2 0.4 0 0.000000 0 0 4.0\n",
      "r.txt");
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].from_stamp_ns, 976052905167303000);
  EXPECT_EQ(r[0].to_stamp_ns, 976052911885496000);
  EXPECT_DOUBLE_EQ(r[0].motion.x_m, -0.05699);
  EXPECT_DOUBLE_EQ(r[0].motion.y_m, -0.12843);
  EXPECT_DOUBLE_EQ(r[0].motion.theta_rad, -1.68221);
  EXPECT_EQ(r[0].line, 2u);
  EXPECT_NEAR(r[1].motion.theta_rad, 4.0 - 2 * std::numbers::pi, 1e-12);  // wrapped
}

TEST(SlamRelations, RejectsMalformedLines) {
  expectRelationsError("1 2 0 0 0 0 0\n", "r.txt:1: expected t1 t2 x y z roll pitch yaw, got 7");
  expectRelationsError("1 2 0 0 0.1 0 0 0\n", "r.txt:1: not a planar relation");
  expectRelationsError("1 2 0 0 0 0 0 0\n1 2 0 inf 0 0 0 0\n", "r.txt:2: non-finite");
  expectRelationsError("1 x 0 0 0 0 0 0\n", "r.txt:1: malformed number");
}

}  // namespace
}  // namespace rmap::datasets
