#pragma once
/// @file binary_features.h
/// Binary keypoint descriptors from OpenCV (ORB, BRISK, AKAZE) behind one
/// interface, so the place recogniser does not depend on the descriptor.
///
/// Each extractor keeps at most max_features keypoints (the strongest by
/// detector response) and returns their descriptors as CV_8U rows (ORB 32
/// bytes, BRISK 64, AKAZE 61). The ORB pyramid is limited to the levels whose
/// image keeps at least min_level_size_px on its shorter side, so small
/// images (240×192) do not spend features on levels too small to describe.

#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace rmap::loop {

enum class DescriptorType { kOrb, kBrisk, kAkaze };

/// "orb", "brisk", "akaze"
std::string toString(DescriptorType type);
/// Inverse of toString; @throws std::invalid_argument for another name.
DescriptorType descriptorTypeFromString(const std::string& name);

/// One image's keypoints (pixels) and binary descriptors.
struct Features {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;  ///< CV_8U, one row per keypoint
};

struct ExtractorOptions {
  int max_features = 500;        ///< strongest keypoints kept
  double scale_factor = 1.2;     ///< ORB pyramid ratio between levels
  int max_levels = 8;            ///< ORB pyramid levels at most ...
  int min_level_size_px = 100;   ///< ... and only those whose shorter side keeps this many pixels
  int edge_threshold_px = 15;    ///< ORB: no keypoints closer to the border (the descriptor patch is padded by reflection)
  int fast_threshold = 20;       ///< ORB FAST threshold (grey levels)
  int brisk_threshold = 30;      ///< BRISK AGAST threshold (grey levels)
  double akaze_threshold = 1e-3; ///< AKAZE detector response threshold
  /// @throws std::invalid_argument naming the first bad field
  void validate() const;
};

/// Pluggable extractor; thread-compatible, not thread-safe (OpenCV detectors keep state).
class FeatureExtractor {
 public:
  virtual ~FeatureExtractor() = default;
  /// @param gray  8-bit single channel, non-empty; @throws std::invalid_argument otherwise
  virtual Features extract(const cv::Mat& gray) = 0;
  virtual DescriptorType type() const = 0;
  /// Bytes per descriptor row (32 ORB, 64 BRISK, 61 AKAZE).
  virtual int descriptorBytes() const = 0;
};

/// @throws std::invalid_argument for invalid options
std::unique_ptr<FeatureExtractor> makeExtractor(DescriptorType type, const ExtractorOptions& options);
std::unique_ptr<FeatureExtractor> makeExtractor(DescriptorType type = DescriptorType::kOrb, int max_features = 500);

/// @throws std::invalid_argument unless `gray` is a non-empty CV_8UC1 image of at least min_side_px on each side
void checkGrayImage(const cv::Mat& gray, int min_side_px = 1);

}  // namespace rmap::loop
