#pragma once
/// @file camera_frames.h
/// Camera images of the robot stream as 8-bit grey frames for place recognition.

#include <opencv2/core/mat.hpp>

#include "rmap/v1/robot_stream.pb.h"

namespace rmap::app {

/// Decodes a JPEG or PNG (OpenCV), or wraps MONO8 / converts RGB8, into an
/// 8-bit single-channel image that owns its pixels.
/// @throws std::invalid_argument when the data does not decode or its size does not match
cv::Mat cameraGray(const v1::CameraImage& image);

}  // namespace rmap::app
