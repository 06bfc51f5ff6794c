#include "loop/panorama.h"

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

namespace rmap::loop {
namespace {

void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("PanoramaOptions: " + what);
}

bool usable(const Eigen::Vector3f& p, double min_range_m) {
  return p.allFinite() && p.squaredNorm() > min_range_m * min_range_m && !p.isZero(0.0f);
}

float elevationOf(const Eigen::Vector3f& p) { return std::atan2(p.z(), std::hypot(p.x(), p.y())); }

/// Row of an elevation among the ring bands (rings ascending, top ring first in the image).
int ringRow(float elevation, const std::vector<float>& rings_ascending, int height) {
  const auto it = std::lower_bound(rings_ascending.begin(), rings_ascending.end(), elevation);
  size_t ring = static_cast<size_t>(it - rings_ascending.begin());
  if (ring == rings_ascending.size() ||
      (ring > 0 && elevation - rings_ascending[ring - 1] < rings_ascending[ring] - elevation)) {
    ring = ring == 0 ? 0 : ring - 1;
  }
  const int rings = static_cast<int>(rings_ascending.size());
  const int band = rings - 1 - static_cast<int>(ring);  // top ring first
  return band * height / rings;
}

/// Mean of the non-empty 8-neighbours into every empty pixel, `iterations` times
/// (azimuth wraps around, elevation does not).
void fillHoles(cv::Mat& grey, cv::Mat& filled, int iterations) {
  const int h = grey.rows, w = grey.cols;
  for (int it = 0; it < iterations; ++it) {
    cv::Mat next = grey.clone();
    cv::Mat next_filled = filled.clone();
    bool changed = false;
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        if (filled.at<uint8_t>(v, u)) continue;
        int sum = 0, n = 0;
        for (int dv = -1; dv <= 1; ++dv) {
          const int vv = v + dv;
          if (vv < 0 || vv >= h) continue;
          for (int du = -1; du <= 1; ++du) {
            const int uu = (u + du + w) % w;
            if (filled.at<uint8_t>(vv, uu)) {
              sum += grey.at<uint8_t>(vv, uu);
              ++n;
            }
          }
        }
        if (n > 0) {
          next.at<uint8_t>(v, u) = static_cast<uint8_t>((sum + n / 2) / n);
          next_filled.at<uint8_t>(v, u) = 1;
          changed = true;
        }
      }
    }
    grey = next;
    filled = next_filled;
    if (!changed) break;
  }
}

}  // namespace

void PanoramaOptions::validate() const {
  require(width_px >= 32 && width_px <= 16384, "width_px must be in [32, 16384]");
  require(height_px >= 32 && height_px <= 4096, "height_px must be in [32, 4096]");
  require(std::isfinite(fov_up_rad) && std::isfinite(fov_down_rad) && fov_up_rad <= std::numbers::pi / 2 &&
              fov_down_rad >= -std::numbers::pi / 2 && fov_down_rad < fov_up_rad,
          "need -pi/2 <= fov_down_rad < fov_up_rad <= pi/2");
  for (float e : ring_elevations_rad) {
    require(std::isfinite(e) && std::abs(e) <= std::numbers::pi / 2, "ring_elevations_rad must be finite, |e| <= pi/2");
  }
  require(ring_elevations_rad.size() <= static_cast<size_t>(height_px), "more rings than height_px rows");
  require(ring_count >= 0 && ring_count <= height_px, "ring_count must be in [0, height_px]");
  require(ring_gap_rad > 0.0 && std::isfinite(ring_gap_rad), "ring_gap_rad must be > 0");
  require(min_range_m >= 0.0 && std::isfinite(min_range_m), "min_range_m must be >= 0");
  require(low_percentile >= 0.0 && high_percentile <= 1.0 && low_percentile < high_percentile,
          "need 0 <= low_percentile < high_percentile <= 1");
  require(fill_iterations >= 0 && fill_iterations <= 64, "fill_iterations must be in [0, 64]");
}

cv::Mat panoramaPoints(const cv::Mat& point_index, std::span<const Eigen::Vector3f> points_sensor) {
  if (point_index.type() != CV_32SC1) throw std::invalid_argument("panoramaPoints: point_index must be CV_32SC1");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cv::Mat points(point_index.size(), CV_32FC3, cv::Scalar::all(nan));
  for (int v = 0; v < point_index.rows; ++v) {
    for (int u = 0; u < point_index.cols; ++u) {
      const int32_t i = point_index.at<int32_t>(v, u);
      if (i < 0) continue;
      if (static_cast<size_t>(i) >= points_sensor.size()) {
        throw std::invalid_argument("panoramaPoints: point index " + std::to_string(i) + " beyond " +
                                    std::to_string(points_sensor.size()) + " points");
      }
      const Eigen::Vector3f& p = points_sensor[static_cast<size_t>(i)];
      points.at<cv::Vec3f>(v, u) = cv::Vec3f(p.x(), p.y(), p.z());
    }
  }
  return points;
}

std::vector<float> estimateRingElevations(std::span<const Eigen::Vector3f> points_sensor, int ring_count,
                                          double gap_rad) {
  if (ring_count < 0) throw std::invalid_argument("estimateRingElevations: ring_count must be >= 0");
  if (!(gap_rad > 0.0)) throw std::invalid_argument("estimateRingElevations: gap_rad must be > 0");
  std::vector<float> elevations;
  elevations.reserve(points_sensor.size());
  for (const Eigen::Vector3f& p : points_sensor) {
    if (usable(p, 0.0)) elevations.push_back(elevationOf(p));
  }
  if (elevations.empty() || elevations.size() < static_cast<size_t>(ring_count)) {
    throw std::invalid_argument("estimateRingElevations: " + std::to_string(elevations.size()) +
                                " valid points, too few for the rings asked for");
  }
  std::sort(elevations.begin(), elevations.end());
  std::vector<size_t> cuts;  // index of the first element of each ring after the first
  if (ring_count == 0) {
    for (size_t i = 1; i < elevations.size(); ++i) {
      if (elevations[i] - elevations[i - 1] > gap_rad) cuts.push_back(i);
    }
  } else if (ring_count > 1) {
    std::vector<size_t> order(elevations.size() - 1);
    for (size_t i = 0; i < order.size(); ++i) order[i] = i + 1;
    std::partial_sort(order.begin(), order.begin() + (ring_count - 1), order.end(), [&](size_t a, size_t b) {
      return elevations[a] - elevations[a - 1] > elevations[b] - elevations[b - 1];
    });
    cuts.assign(order.begin(), order.begin() + (ring_count - 1));
    std::sort(cuts.begin(), cuts.end());
  }
  std::vector<float> rings;
  size_t begin = 0;
  cuts.push_back(elevations.size());
  for (size_t end : cuts) {
    rings.push_back(elevations[begin + (end - begin) / 2]);
    begin = end;
  }
  return rings;
}

cv::Mat projectPanorama(std::span<const Eigen::Vector3f> points_sensor, std::span<const float> intensities,
                        const PanoramaOptions& options) {
  cv::Mat unused;
  return projectPanorama(points_sensor, intensities, options, unused);
}

cv::Mat projectPanorama(std::span<const Eigen::Vector3f> points_sensor, std::span<const float> intensities,
                        const PanoramaOptions& options, cv::Mat& point_index) {
  options.validate();
  if (points_sensor.size() != intensities.size()) {
    throw std::invalid_argument("projectPanorama: " + std::to_string(points_sensor.size()) + " points but " +
                                std::to_string(intensities.size()) + " intensities");
  }
  if (points_sensor.size() > static_cast<size_t>(INT32_MAX)) throw std::invalid_argument("projectPanorama: too many points");
  const int w = options.width_px, h = options.height_px;
  const bool by_ring = options.projection == PanoramaProjection::kRingByColumn;
  std::vector<float> rings;
  if (by_ring) {
    rings = options.ring_elevations_rad;
    if (rings.empty()) {
      rings = estimateRingElevations(points_sensor, options.ring_count, options.ring_gap_rad);
      if (rings.size() > static_cast<size_t>(h)) {
        throw std::invalid_argument("projectPanorama: found " + std::to_string(rings.size()) +
                                    " rings, more than height_px; set ring_count or a wider ring_gap_rad");
      }
    }
    std::sort(rings.begin(), rings.end());
  }

  // z-buffer: closest point per pixel, its intensity.
  std::vector<float> depth(static_cast<size_t>(w) * h, std::numeric_limits<float>::infinity());
  std::vector<float> value(depth.size(), 0.0f);
  std::vector<int32_t> source(depth.size(), -1);
  const double fov = options.fov_up_rad - options.fov_down_rad;
  for (size_t i = 0; i < points_sensor.size(); ++i) {
    const Eigen::Vector3f& p = points_sensor[i];
    const float intensity = intensities[i];
    if (!usable(p, options.min_range_m) || !std::isfinite(intensity)) continue;
    const double azimuth = std::atan2(p.y(), p.x());
    int u = static_cast<int>(std::floor((std::numbers::pi - azimuth) / (2.0 * std::numbers::pi) * w));
    u = ((u % w) + w) % w;
    const float elevation = elevationOf(p);
    int v;
    if (by_ring) {
      v = ringRow(elevation, rings, h);
    } else {
      if (elevation > options.fov_up_rad || elevation < options.fov_down_rad) continue;
      v = std::min(h - 1, static_cast<int>((options.fov_up_rad - elevation) / fov * h));
    }
    const size_t k = static_cast<size_t>(v) * w + u;
    const float r = p.squaredNorm();
    if (r < depth[k]) {
      depth[k] = r;
      value[k] = std::max(0.0f, intensity);
      source[k] = static_cast<int32_t>(i);
    }
  }

  std::vector<float> kept;
  for (size_t k = 0; k < depth.size(); ++k) {
    if (std::isfinite(depth[k])) kept.push_back(value[k]);
  }
  cv::Mat grey(h, w, CV_8UC1, cv::Scalar(0));
  cv::Mat filled(h, w, CV_8UC1, cv::Scalar(0));
  point_index = cv::Mat(h, w, CV_32SC1);
  std::copy(source.begin(), source.end(), point_index.begin<int32_t>());
  if (kept.empty()) return grey;
  auto percentile = [&](double q) {
    const size_t n = static_cast<size_t>(std::lround(q * static_cast<double>(kept.size() - 1)));
    std::nth_element(kept.begin(), kept.begin() + static_cast<std::ptrdiff_t>(n), kept.end());
    return kept[n];
  };
  const float lo = percentile(options.low_percentile);
  const float hi = percentile(options.high_percentile);
  const float scale = hi > lo ? 254.0f / (hi - lo) : 0.0f;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const size_t k = static_cast<size_t>(v) * w + u;
      if (!std::isfinite(depth[k])) continue;
      const float g = hi > lo ? 1.0f + (value[k] - lo) * scale : 128.0f;
      grey.at<uint8_t>(v, u) = static_cast<uint8_t>(std::clamp(std::lround(g), 1L, 255L));
      filled.at<uint8_t>(v, u) = 1;
    }
  }
  if (by_ring) {
    // Every row of a ring's band repeats the ring's row.
    const int r = static_cast<int>(rings.size());
    for (int band = 0; band < r; ++band) {
      const int first = band * h / r, end = (band + 1) * h / r;
      for (int v = first + 1; v < end; ++v) {
        grey.row(first).copyTo(grey.row(v));
        filled.row(first).copyTo(filled.row(v));
      }
    }
  }
  fillHoles(grey, filled, options.fill_iterations);
  return grey;
}

}  // namespace rmap::loop
