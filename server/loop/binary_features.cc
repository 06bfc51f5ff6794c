#include "loop/binary_features.h"

#include <algorithm>
#include <cmath>
#include <opencv2/features2d.hpp>
#include <stdexcept>

namespace rmap::loop {

std::string toString(DescriptorType type) {
  switch (type) {
    case DescriptorType::kOrb: return "orb";
    case DescriptorType::kBrisk: return "brisk";
    case DescriptorType::kAkaze: return "akaze";
  }
  return "unknown";
}

DescriptorType descriptorTypeFromString(const std::string& name) {
  for (DescriptorType t : {DescriptorType::kOrb, DescriptorType::kBrisk, DescriptorType::kAkaze}) {
    if (toString(t) == name) return t;
  }
  throw std::invalid_argument("unknown descriptor '" + name + "' (orb, brisk, akaze)");
}

void ExtractorOptions::validate() const {
  auto require = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("ExtractorOptions: ") + what);
  };
  require(max_features >= 1, "max_features must be >= 1");
  require(scale_factor > 1.0 && scale_factor <= 2.0, "scale_factor must be in (1, 2]");
  require(max_levels >= 1 && max_levels <= 16, "max_levels must be in [1, 16]");
  require(min_level_size_px >= 16, "min_level_size_px must be >= 16");
  require(edge_threshold_px >= 3, "edge_threshold_px must be >= 3");
  require(fast_threshold >= 1 && fast_threshold <= 255, "fast_threshold must be in [1, 255]");
  require(brisk_threshold >= 1 && brisk_threshold <= 255, "brisk_threshold must be in [1, 255]");
  require(akaze_threshold > 0.0, "akaze_threshold must be > 0");
}

void checkGrayImage(const cv::Mat& gray, int min_side_px) {
  if (gray.empty()) throw std::invalid_argument("image is empty");
  if (gray.type() != CV_8UC1) throw std::invalid_argument("image must be 8-bit single channel (CV_8UC1)");
  if (gray.cols < min_side_px || gray.rows < min_side_px) {
    throw std::invalid_argument("image is " + std::to_string(gray.cols) + "x" + std::to_string(gray.rows) +
                                " px, needs at least " + std::to_string(min_side_px) + " px on each side");
  }
}

namespace {

class OrbExtractor final : public FeatureExtractor {
 public:
  explicit OrbExtractor(const ExtractorOptions& o) : options_(o) {}

  Features extract(const cv::Mat& gray) override {
    checkGrayImage(gray);
    const int levels = pyramidLevels(std::min(gray.cols, gray.rows));
    if (!orb_ || levels != orb_->getNLevels()) {
      orb_ = cv::ORB::create(options_.max_features, static_cast<float>(options_.scale_factor), levels,
                             options_.edge_threshold_px, 0, 2, cv::ORB::HARRIS_SCORE, 31, options_.fast_threshold);
    }
    Features f;
    orb_->detectAndCompute(gray, cv::noArray(), f.keypoints, f.descriptors);
    return f;
  }
  DescriptorType type() const override { return DescriptorType::kOrb; }
  int descriptorBytes() const override { return 32; }

 private:
  int pyramidLevels(int short_side_px) const {
    int levels = 1;
    double side = short_side_px / options_.scale_factor;
    while (levels < options_.max_levels && side >= options_.min_level_size_px) {
      ++levels;
      side /= options_.scale_factor;
    }
    return levels;
  }

  ExtractorOptions options_;
  cv::Ptr<cv::ORB> orb_;
};

/// Detects, keeps the strongest max_features, then describes: BRISK and AKAZE have no feature cap of their own.
class CappedExtractor final : public FeatureExtractor {
 public:
  CappedExtractor(cv::Ptr<cv::Feature2D> f2d, DescriptorType type, int bytes, int max_features)
      : f2d_(std::move(f2d)), type_(type), bytes_(bytes), max_features_(max_features) {}

  Features extract(const cv::Mat& gray) override {
    checkGrayImage(gray);
    Features f;
    f2d_->detect(gray, f.keypoints);
    cv::KeyPointsFilter::retainBest(f.keypoints, max_features_);
    if (static_cast<int>(f.keypoints.size()) > max_features_) f.keypoints.resize(max_features_);  // ties at the cut
    f2d_->compute(gray, f.keypoints, f.descriptors);
    if (f.descriptors.empty()) f.descriptors.create(0, bytes_, CV_8U);
    return f;
  }
  DescriptorType type() const override { return type_; }
  int descriptorBytes() const override { return bytes_; }

 private:
  cv::Ptr<cv::Feature2D> f2d_;
  DescriptorType type_;
  int bytes_;
  int max_features_;
};

}  // namespace

std::unique_ptr<FeatureExtractor> makeExtractor(DescriptorType type, const ExtractorOptions& options) {
  options.validate();
  switch (type) {
    case DescriptorType::kOrb: return std::make_unique<OrbExtractor>(options);
    case DescriptorType::kBrisk:
      return std::make_unique<CappedExtractor>(cv::BRISK::create(options.brisk_threshold, 3), type, 64,
                                               options.max_features);
    case DescriptorType::kAkaze:
      return std::make_unique<CappedExtractor>(
          cv::AKAZE::create(cv::AKAZE::DESCRIPTOR_MLDB, 0, 3, static_cast<float>(options.akaze_threshold)), type, 61,
          options.max_features);
  }
  throw std::invalid_argument("unknown descriptor type");
}

std::unique_ptr<FeatureExtractor> makeExtractor(DescriptorType type, int max_features) {
  ExtractorOptions o;
  o.max_features = max_features;
  return makeExtractor(type, o);
}

}  // namespace rmap::loop
