#pragma once
/// @file same_grey_recognizer.h
/// A test double of a place recognizer for the tests of the loop closure
/// plumbing: a frame matches the first earlier frame of the same mean grey,
/// two or more frames back; the score is the frame's mean grey / 255.

#include <future>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/place_recognizer.h"

namespace rmap::app::testing {

class SameGreyRecognizer : public PlaceRecognizer {
 public:
  /// @param gate  each frame waits for it first, when valid
  explicit SameGreyRecognizer(std::shared_future<void> gate = {}) : gate_(std::move(gate)) {}
  std::optional<Match> addFrame(const PlaceImage& image, const std::string& /*robot_id*/) override {
    if (gate_.valid()) gate_.wait();
    const cv::Mat& gray = image.gray;
    if (gray.type() != CV_8UC1) throw std::invalid_argument("not 8-bit grey");
    const double mean = cv::mean(gray)[0];
    means_.push_back(mean);
    for (size_t i = 0; i + 2 < means_.size(); ++i) {
      if (means_[i] == mean) return Match{static_cast<int64_t>(i), mean / 255.0, std::nullopt};
    }
    return std::nullopt;
  }

 private:
  std::shared_future<void> gate_;
  std::vector<double> means_;
};

}  // namespace rmap::app::testing
