#include "app/image_codecs.h"

#include <png.h>

#include <stdexcept>

namespace rmap::app {

namespace {

void appendBytes(png_structp png, png_bytep data, png_size_t length) {
  static_cast<std::string*>(png_get_io_ptr(png))->append(reinterpret_cast<const char*>(data), length);
}

void checkSize(int width, int height, size_t bytes, size_t channels) {
  if (width <= 0 || height <= 0 || bytes != static_cast<size_t>(width) * static_cast<size_t>(height) * channels) {
    throw std::invalid_argument("image of " + std::to_string(width) + "x" + std::to_string(height) + " needs " +
                                std::to_string(channels) + " byte(s) per pixel, got " + std::to_string(bytes) +
                                " bytes");
  }
}

}  // namespace

std::string encodePng(const GrayAlphaImage& image) {
  checkSize(image.width, image.height, image.pixels.size(), 2);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) throw std::runtime_error("libpng: cannot create a write struct");
  png_infop info = png_create_info_struct(png);
  std::string out;
  // libpng reports errors by longjmp: nothing with a destructor may be created between here and the writes.
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw std::runtime_error("libpng: encoding failed");
  }
  png_set_write_fn(png, &out, appendBytes, nullptr);
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.width), static_cast<png_uint_32>(image.height), 8,
               PNG_COLOR_TYPE_GRAY_ALPHA, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  // Tiles are made per request: fast compression, the rasters are mostly flat anyway.
  png_set_compression_level(png, 3);
  png_write_info(png, info);
  const size_t stride = static_cast<size_t>(image.width) * 2;
  for (int row = 0; row < image.height; ++row) {
    png_write_row(png, const_cast<png_bytep>(image.pixels.data() + static_cast<size_t>(row) * stride));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

std::string encodePgm(int width, int height, std::span<const uint8_t> pixels) {
  checkSize(width, height, pixels.size(), 1);
  std::string out = "P5\n" + std::to_string(width) + " " + std::to_string(height) + "\n255\n";
  out.append(reinterpret_cast<const char*>(pixels.data()), pixels.size());
  return out;
}

}  // namespace rmap::app
