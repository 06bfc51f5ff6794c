#pragma once
/// @file camera_image_file.h
/// Camera images on disk, as a robot streams them: the encoded bytes of a
/// JPEG or PNG file, checked by decoding them once (OpenCV).

#include <cstdint>
#include <string>
#include <vector>

namespace rmap::datasets {

enum class ImageEncoding { kJpeg, kPng };

struct CameraImageFile {
  ImageEncoding encoding = ImageEncoding::kPng;
  int width_px = 0;
  int height_px = 0;
  std::string bytes;  ///< the file's content, as encoded
};

/// Whether the name ends in .png, .jpg or .jpeg (any case).
bool isImageFileName(const std::string& path);

/// The image files (isImageFileName) of a folder, sorted by name; not recursive.
/// @throws std::runtime_error naming the folder when it cannot be listed or holds no image
std::vector<std::string> listImageFolder(const std::string& dir);

/// Reads and decodes an image file; the encoding comes from the content's
/// signature (JPEG FF D8 FF, PNG 89 50 4E 47), not from the name.
/// @throws std::runtime_error naming the file when it cannot be read, is
///         neither JPEG nor PNG, or does not decode (truncated, corrupt)
CameraImageFile readCameraImageFile(const std::string& path);

}  // namespace rmap::datasets
