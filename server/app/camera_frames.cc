#include "app/camera_frames.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

namespace rmap::app {

cv::Mat cameraGray(const v1::CameraImage& image) {
  const std::string& data = image.data();
  const auto raw = [&](int type, size_t channels) {
    const size_t expected = size_t{image.width()} * image.height() * channels;
    if (image.width() == 0 || image.height() == 0 || data.size() != expected) {
      throw std::invalid_argument("raw image of " + std::to_string(image.width()) + "x" +
                                  std::to_string(image.height()) + " needs " + std::to_string(expected) +
                                  " bytes, got " + std::to_string(data.size()));
    }
    // Wraps the message's bytes; the callers copy or convert before the message goes.
    return cv::Mat(static_cast<int>(image.height()), static_cast<int>(image.width()), type,
                   const_cast<char*>(data.data()));
  };
  switch (image.encoding()) {
    case v1::CameraImage::JPEG:
    case v1::CameraImage::PNG: {
      const cv::Mat bytes(1, static_cast<int>(data.size()), CV_8U, const_cast<char*>(data.data()));
      cv::Mat gray = cv::imdecode(bytes, cv::IMREAD_GRAYSCALE);
      if (gray.empty()) throw std::invalid_argument("image data does not decode");
      return gray;
    }
    case v1::CameraImage::MONO8: return raw(CV_8UC1, 1).clone();
    case v1::CameraImage::RGB8: {
      cv::Mat gray;
      cv::cvtColor(raw(CV_8UC3, 3), gray, cv::COLOR_RGB2GRAY);
      return gray;
    }
    default: break;
  }
  throw std::invalid_argument("image encoding must be JPEG, PNG, MONO8 or RGB8");
}

}  // namespace rmap::app
