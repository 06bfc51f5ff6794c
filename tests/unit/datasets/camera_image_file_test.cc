#include "datasets/camera_image_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace rmap::datasets {
namespace {

namespace fs = std::filesystem;

class CameraImageFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rmap_camera_image_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& bytes) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << bytes;
    return p.string();
  }
  static std::string encoded(const std::string& ext) {
    cv::Mat image(12, 20, CV_8UC3, cv::Scalar(10, 200, 30));
    std::vector<uint8_t> bytes;
    cv::imencode(ext, image, bytes);
    return std::string(bytes.begin(), bytes.end());
  }
  fs::path dir_;
};

TEST_F(CameraImageFileTest, ListsAndReadsPngAndJpeg) {
  write("b.JPG", encoded(".jpg"));
  write("a.png", encoded(".png"));
  write("notes.txt", "not an image");
  const std::vector<std::string> files = listImageFolder(dir_.string());
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(fs::path(files[0]).filename(), "a.png");
  const CameraImageFile png = readCameraImageFile(files[0]);
  EXPECT_EQ(png.encoding, ImageEncoding::kPng);
  EXPECT_EQ(png.width_px, 20);
  EXPECT_EQ(png.height_px, 12);
  EXPECT_EQ(readCameraImageFile(files[1]).encoding, ImageEncoding::kJpeg);
}

TEST_F(CameraImageFileTest, BadFilesAreNamed) {
  const std::string png = encoded(".png");
  const std::string truncated = write("cut.png", png.substr(0, png.size() / 2));
  const std::string text = write("text.png", "hello");
  EXPECT_THROW(
      {
        try {
          readCameraImageFile(truncated);
        } catch (const std::runtime_error& e) {
          EXPECT_NE(std::string(e.what()).find("cut.png: does not decode"), std::string::npos) << e.what();
          throw;
        }
      },
      std::runtime_error);
  try {
    readCameraImageFile(text);
    ADD_FAILURE() << "accepted a text file";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("text.png: offset 0: neither a JPEG nor a PNG"), std::string::npos);
  }
  const fs::path empty = dir_ / "empty";
  fs::create_directories(empty);
  EXPECT_THROW(listImageFolder(empty.string()), std::runtime_error);
}

}  // namespace
}  // namespace rmap::datasets
