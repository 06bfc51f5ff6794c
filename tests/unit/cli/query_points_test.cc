#include "cli/query_points.h"

#include <gtest/gtest.h>

namespace rmap::cli {
namespace {

TEST(QueryPoints, ParsesCommaSeparatedNumbers) {
  EXPECT_EQ(parseNumbers("1.5,-2,3e-1", 3, "--point"), (std::vector<double>{1.5, -2.0, 0.3}));
  EXPECT_EQ(parseNumbers(" 0, 1 ,2,3,4,5 ", 6, "--box"), (std::vector<double>{0, 1, 2, 3, 4, 5}));
}

TEST(QueryPoints, RefusesWrongCountsAndNonNumbers) {
  for (const char* bad : {"1,2", "1,2,3,4", "1,,2,3", "1,2,x", "1,2,nan", "1,2,inf", "", "1 2 3"}) {
    try {
      parseNumbers(bad, 3, "--point");
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("--point must be 3 finite numbers"), std::string::npos) << e.what();
    }
  }
}

TEST(QueryPoints, ReadsBatchLinesWithSpacesOrCommasAndComments) {
  const std::vector<Eigen::Vector3d> points =
      parsePointLines("# x y z\n1 2 3\n\n  4.5\t-1   0 \r\n7,8,9\n# end", "points.txt");
  ASSERT_EQ(points.size(), 3u);
  EXPECT_EQ(points[0], Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(points[1], Eigen::Vector3d(4.5, -1, 0));
  EXPECT_EQ(points[2], Eigen::Vector3d(7, 8, 9));
  EXPECT_TRUE(parsePointLines("", "empty.txt").empty());
}

TEST(QueryPoints, BatchErrorsNameFileAndLine) {
  try {
    parsePointLines("1 2 3\n4 5\n", "points.txt");
    ADD_FAILURE() << "a line of two numbers was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("points.txt:2:"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parsePointLines("1 2 nan\n", "p"), std::invalid_argument);
  EXPECT_THROW(parsePointLines("1,2 3\n", "p"), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::cli
