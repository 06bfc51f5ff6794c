#include "app/image_codecs.h"

#include <gtest/gtest.h>
#include <png.h>

namespace rmap::app {
namespace {

TEST(ImageCodecs, PngDecodesToTheSamePixels) {
  GrayAlphaImage image{3, 2, {0, 255, 10, 0, 20, 128, 30, 255, 40, 255, 250, 1}};
  const std::string png = encodePng(image);
  ASSERT_GE(png.size(), 8u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  png_image decoded{};
  decoded.version = PNG_IMAGE_VERSION;
  ASSERT_TRUE(png_image_begin_read_from_memory(&decoded, png.data(), png.size()));
  EXPECT_EQ(decoded.width, 3u);
  EXPECT_EQ(decoded.height, 2u);
  decoded.format = PNG_FORMAT_GA;
  std::vector<uint8_t> pixels(PNG_IMAGE_SIZE(decoded));
  ASSERT_TRUE(png_image_finish_read(&decoded, nullptr, pixels.data(), 0, nullptr));
  EXPECT_EQ(pixels, image.pixels);
}

TEST(ImageCodecs, PngRefusesAPixelBufferOfTheWrongSize) {
  EXPECT_THROW(encodePng({2, 2, std::vector<uint8_t>(7)}), std::invalid_argument);
  EXPECT_THROW(encodePng({0, 2, {}}), std::invalid_argument);
}

TEST(ImageCodecs, PgmHasTheP5HeaderThenTheRows) {
  const std::vector<uint8_t> pixels{0, 254, 205, 7, 8, 9};
  const std::string pgm = encodePgm(3, 2, pixels);
  const std::string header = "P5\n3 2\n255\n";
  ASSERT_EQ(pgm.size(), header.size() + 6);
  EXPECT_EQ(pgm.substr(0, header.size()), header);
  EXPECT_EQ(std::vector<uint8_t>(pgm.begin() + static_cast<long>(header.size()), pgm.end()), pixels);
  EXPECT_THROW(encodePgm(2, 2, pixels), std::invalid_argument);
}

}  // namespace
}  // namespace rmap::app
