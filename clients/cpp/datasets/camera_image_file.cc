#include "datasets/camera_image_file.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

namespace rmap::datasets {

bool isImageFileName(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

std::vector<std::string> listImageFolder(const std::string& dir) {
  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    if (entry.is_regular_file() && isImageFileName(entry.path().string())) files.push_back(entry.path().string());
  }
  if (ec) throw std::runtime_error(dir + ": cannot list: " + ec.message());
  if (files.empty()) throw std::runtime_error(dir + ": no .png, .jpg or .jpeg file");
  std::sort(files.begin(), files.end());
  return files;
}

CameraImageFile readCameraImageFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open");
  CameraImageFile image;
  image.bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (in.bad()) throw std::runtime_error(path + ": read error");
  const auto starts = [&](std::string_view magic) { return image.bytes.compare(0, magic.size(), magic) == 0; };
  if (starts("\xFF\xD8\xFF")) {
    image.encoding = ImageEncoding::kJpeg;
  } else if (starts("\x89PNG")) {
    image.encoding = ImageEncoding::kPng;
  } else {
    throw std::runtime_error(path + ": offset 0: neither a JPEG nor a PNG signature");
  }
  const std::vector<uint8_t> data(image.bytes.begin(), image.bytes.end());
  const cv::Mat decoded = cv::imdecode(data, cv::IMREAD_UNCHANGED);
  if (decoded.empty()) throw std::runtime_error(path + ": does not decode (truncated or corrupt image)");
  image.width_px = decoded.cols;
  image.height_px = decoded.rows;
  return image;
}

}  // namespace rmap::datasets
