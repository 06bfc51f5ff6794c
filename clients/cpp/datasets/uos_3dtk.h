#pragma once
/// @file uos_3dtk.h
/// Reader of 3DTK (slam6d) scan folders in the "uos" format.
///
/// Files per scan NNN (000, 001, … up to the first missing one):
/// - `scanNNN.3d`: one point `x y z` per line in the scanner frame, an
///   optional first line `W x H`, '#' comments;
/// - `scanNNN.frames` (optional): one pose per line, 16 numbers of a 4×4
///   column-major matrix then a type code; the last line is the final
///   registered pose and is used when the file has any line;
/// - `scanNNN.pose` (otherwise): line 1 translation, line 2 Euler angles
///   rx ry rz in degrees, rotation R = Rx(rx)·Ry(ry)·Rz(rz) (3DTK's
///   EulerToMatrix4; it matches the .frames matrices of the example data).
/// The uos frame is left-handed, centimetres, x right, y up, z forward.
/// Points are posed there (p' = R·p + t), then converted to right-handed
/// metres: x = z/100 (forward), y = −x/100 (left), z = y/100 (up).

#include <cstddef>
#include <string>
#include <vector>

#include "datasets/point_scan.h"

namespace rmap::datasets {

/// Returns closer than this are the scanner's own housing (3DTK example config `min=48`).
inline constexpr double kUosMinRangeCm = 48.0;
/// Returns at or beyond this are dropped: no-return readings sit at ≈3276 cm,
/// and the few readings between 3000 cm and there are stray.
inline constexpr double kUosMaxRangeCm = 3000.0;

/// Counts over all scans of one readUos3dtk call (reset at its start).
struct UosReadStats {
  size_t points_read = 0;         ///< point lines in the .3d files
  size_t dropped_near = 0;        ///< range < kUosMinRangeCm
  size_t dropped_far = 0;         ///< range ≥ kUosMaxRangeCm
  size_t dropped_non_finite = 0;  ///< a coordinate is NaN or infinite
  size_t poses_from_frames = 0;   ///< scans posed by their .frames file (the others by .pose)
};

/// Reads scan000, scan001, … of `dir` until the first missing .3d file.
/// @throws std::runtime_error naming the file (and line) when scan000.3d is
///         missing, a scan has neither .frames nor .pose, or a file is malformed
std::vector<PointScan> readUos3dtk(const std::string& dir, UosReadStats* stats = nullptr);

}  // namespace rmap::datasets
