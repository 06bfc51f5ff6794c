#include "loop/loop_bench.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <unistd.h>

#include "../loop/test_images.h"

namespace rmap::bench {
namespace {

namespace fs = std::filesystem;

TEST(LoopBench, RunsAFolderAndWritesJsonCsvAndPlot) {
  const fs::path dir = fs::temp_directory_path() / ("rmap_loop_bench_" + std::to_string(::getpid()));
  fs::create_directories(dir / "images");
  // Four places, then the first two again (moved a little): frames 4 and 5 close loops on 0 and 1.
  const uint32_t places[] = {1, 2, 3, 4, 1, 2};
  for (int i = 0; i < 6; ++i) {
    cv::Mat img = loop::test::texturedScene(places[i]);
    if (i >= 4) img = loop::test::shifted(img, 5.0, 2.0);
    char name[32];
    std::snprintf(name, sizeof name, "frame_%03d.png", i);
    ASSERT_TRUE(cv::imwrite((dir / "images" / name).string(), img));
  }
  std::ofstream(dir / "notes.txt") << "not an image\n";
  std::ofstream(dir / "images" / "notes.txt") << "not an image\n";
  std::ofstream(dir / "pairs.txt") << "# query reference\n4 0\n5 1\n";

  LoopBenchOptions o;
  o.images_dir = (dir / "images").string();
  o.ground_truth = (dir / "pairs.txt").string();
  o.json_out = (dir / "out.json").string();
  o.csv_prefix = (dir / "out").string();
  o.detector.exclusion_window_frames = 2;
  EXPECT_EQ(listImages(o.images_dir).size(), 6u);
  ASSERT_EQ(runLoopBench(o), 0);

  std::ifstream in(o.json_out);
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j.at("frames"), 6);
  EXPECT_EQ(j.at("loop_queries"), 2);
  for (const char* k : {"tol0", "tol2", "tol40"}) {
    EXPECT_DOUBLE_EQ(j.at("recall_at_100_precision").at(k).get<double>(), 1.0) << k;
    EXPECT_DOUBLE_EQ(j.at("precision").at(k).get<double>(), 1.0) << k;
    EXPECT_DOUBLE_EQ(j.at("recall").at(k).get<double>(), 1.0) << k;
    EXPECT_DOUBLE_EQ(j.at("auc").at(k).get<double>(), 1.0) << k;
    EXPECT_TRUE(fs::exists(o.csv_prefix + "_pr_" + k + ".csv"));
  }
  EXPECT_GT(j.at("ms_per_frame_mean").get<double>(), 0.0);
  EXPECT_GE(j.at("ms_per_frame_p95").get<double>(), j.at("ms_per_frame_mean").get<double>() * 0.5);
  EXPECT_GT(j.at("vocabulary_words").get<int>(), 100);
  EXPECT_TRUE(j.at("machine").contains("cpu"));
  EXPECT_FALSE(cv::imread(o.csv_prefix + "_pr.png").empty());
  std::ifstream frames(o.csv_prefix + "_frames.csv");
  std::string line;
  int lines = 0;
  while (std::getline(frames, line)) ++lines;
  EXPECT_EQ(lines, 7);  // header + one per frame
  fs::remove_all(dir);
}

TEST(LoopBench, MissingFoldersAndFilesAreReported) {
  EXPECT_THROW(listImages("/nonexistent/folder"), std::runtime_error);
  const fs::path empty = fs::temp_directory_path() / ("rmap_loop_bench_empty_" + std::to_string(::getpid()));
  fs::create_directories(empty);
  EXPECT_THROW(listImages(empty.string()), std::runtime_error);
  fs::remove_all(empty);
}

}  // namespace
}  // namespace rmap::bench
