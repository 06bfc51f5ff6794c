#include "cli/replay_format.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "temp_files.h"

namespace rmap::cli {
namespace {

namespace fs = std::filesystem;

using ReplayFormatTest = TempFilesTest;

TEST_F(ReplayFormatTest, DetectsFormatsByNameAndFolder) {
  EXPECT_EQ(detectReplayFormat({write("a.log.gz", "")}), ReplayFormat::kCarmen);
  EXPECT_EQ(detectReplayFormat({write("a.clf", "")}), ReplayFormat::kCarmen);
  EXPECT_EQ(detectReplayFormat({write("scan.dat.bz2", "")}), ReplayFormat::kXyzText);
  EXPECT_EQ(detectReplayFormat({write("x.graph", "")}), ReplayFormat::kOctomapGraph);
  EXPECT_EQ(detectReplayFormat({write("0.bin", ""), write("1.bin", "")}), ReplayFormat::kVelodyneBin);
  EXPECT_EQ(detectReplayFormat({write("c.PCD", "")}), ReplayFormat::kPcd);
  write("uos/scan000.3d", "");
  EXPECT_EQ(detectReplayFormat({(dir_ / "uos").string()}), ReplayFormat::kUos3dtk);
  write("cam/0001.jpg", "");
  EXPECT_EQ(detectReplayFormat({(dir_ / "cam").string()}), ReplayFormat::kImages);
  EXPECT_THROW(detectReplayFormat({write("a.ply", ""), write("b.pcd", "")}), std::runtime_error);
  EXPECT_THROW(detectReplayFormat({write("a.unknown", "")}), std::runtime_error);
  EXPECT_THROW(detectReplayFormat({(dir_ / "missing.ply").string()}), std::runtime_error);
  EXPECT_EQ(parseReplayFormat("3dtk"), ReplayFormat::kUos3dtk);
  EXPECT_THROW(parseReplayFormat("las"), std::invalid_argument);
}

TEST_F(ReplayFormatTest, DefaultRobotId) {
  EXPECT_EQ(defaultRobotId("/data/intel-corrected.log.gz"), "intel-corrected");
  EXPECT_EQ(defaultRobotId("seq 07/"), "seq-07");
  EXPECT_EQ(defaultRobotId("/x/.hidden"), "replay");
  EXPECT_EQ(defaultRobotId(std::string(80, 'a') + ".bin").size(), 64u);
}

}  // namespace
}  // namespace rmap::cli
