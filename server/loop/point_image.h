#pragma once
/// @file point_image.h
/// Point images: the 3D point each pixel of an image shows, so keypoints
/// found in the image can be lifted to metres (laser-intensity panoramas,
/// whose pixels come from the cloud; an RGB-D camera's organised cloud).
/// CV_32FC3, metres, in the sensor's frame; NaN where a pixel shows no point
/// of its own (no return, or filled in from its neighbours).

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <optional>
#include <utility>

namespace rmap::loop {

/// A frame for place recognition: its 8-bit grey image and, when its pixels
/// show 3D points (laser-intensity panoramas), its point image, else empty.
struct PlaceImage {
  PlaceImage(cv::Mat gray_image, cv::Mat points_image = {})  // NOLINT(google-explicit-constructor): an image alone is a frame
      : gray(std::move(gray_image)), points_m(std::move(points_image)) {}
  cv::Mat gray;
  cv::Mat points_m;
};

/// Whether `points_m` is a point image of an image of `size`.
bool isPointImage(const cv::Mat& points_m, cv::Size size);

/// The point of the pixel nearest to `pixel` (Chebyshev distance, at most
/// radius_px) that has one; nullopt when none does.
/// @param radius_px  ≥ 0; a panorama's hole filling reaches that many pixels from a real one
std::optional<Eigen::Vector3f> pointNear(const cv::Mat& points_m, cv::Point2f pixel, int radius_px);

}  // namespace rmap::loop
