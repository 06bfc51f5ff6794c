#include "datasets/kitti_velodyne.h"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "datasets/compressed_file.h"

namespace rmap::datasets {

VelodyneFrame parseVelodyneBin(std::string_view bytes, const std::string& source) {
  constexpr size_t kRecord = 4 * sizeof(float);
  if (bytes.size() % kRecord != 0) {
    throw std::runtime_error(source + ": " + std::to_string(bytes.size()) +
                             " bytes is not a whole number of 16-byte x y z intensity records");
  }
  const size_t n = bytes.size() / kRecord;
  VelodyneFrame frame;
  frame.points_m.reserve(n);
  frame.intensities.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    float v[4];
    std::memcpy(v, bytes.data() + i * kRecord, kRecord);
    for (int k = 0; k < 4; ++k) {
      if (!std::isfinite(v[k])) {
        throw std::runtime_error(source + ": offset " + std::to_string(i * kRecord + 4 * k) + ": point " +
                                 std::to_string(i) + " has a non-finite value");
      }
    }
    frame.points_m.emplace_back(v[0], v[1], v[2]);
    frame.intensities.push_back(v[3]);
  }
  return frame;
}

VelodyneFrame readVelodyneBin(const std::string& path) { return parseVelodyneBin(readFileMaybeCompressed(path), path); }

}  // namespace rmap::datasets
