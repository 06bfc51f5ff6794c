#pragma once
/// @file replay_source.h
/// Datasets on disk as the messages of one robot's stream, for `rmap replay`.
///
/// A source is a sequence of frames: each frame is one RobotMessage body
/// (LaserScan2D, PointCloud or CameraImage) with its stamp. Formats read in
/// one piece (CARMEN logs, `.graph` scan graphs, `scan.dat` text clouds, 3DTK
/// folders) are parsed and checked entirely when the source is opened; formats
/// of one file per frame (velodyne `.bin`, PLY, PCD, images) have their file
/// list and poses checked when opened and each file parsed and checked whole
/// before its frame is returned, so a bad file never sends part of itself.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "cli/replay_format.h"
#include "rmap/v1/robot_stream.pb.h"

namespace rmap::cli {

struct ReplaySourceOptions {
  /// Poses of the frames (KITTI 3×4 or TUM lines, see datasets/pose_file.h),
  /// one per frame, for velodyne, PLY, PCD and image frames. Without it,
  /// clouds are in the map frame with the sensor at the origin and images
  /// carry no pose.
  std::string poses_path;
  /// Stamp step for frames the dataset gives no stamp (s).
  double period_s = 0.1;
  /// Laser above the robot base for CARMEN logs: the height of the planar
  /// cloud the server puts into the 3D map (m).
  double laser_height_m = 0.0;
};

/// One message of the stream, without its sequence number.
struct ReplayFrame {
  rmap::v1::RobotMessage message;
  int64_t stamp_ns = 0;
  uint64_t points = 0;          ///< cloud points (non-finite ones dropped), or 2D beams
  uint64_t dropped_points = 0;  ///< non-finite points the protocol cannot carry
};

struct ReplaySource {
  ReplayFormat format = ReplayFormat::kCarmen;
  std::vector<rmap::v1::SensorDescription> sensors;  ///< for the Hello
  size_t frames = 0;
  /// Frame i (0 ≤ i < frames), in stream order.
  /// @throws std::runtime_error naming the file (and line or offset) when it is bad
  std::function<ReplayFrame(size_t)> frame;
  /// Whether frame() reads files (one per frame) rather than returning what open already checked.
  bool reads_per_frame = false;
  std::vector<std::string> notes;  ///< what the reader skipped or assumed, for the user
};

/// Opens `paths` as `format`.
/// @throws std::runtime_error naming the file (and line or offset) for
///         unreadable or malformed input, a poses file whose count differs
///         from the frames', or a CARMEN log given with other files
ReplaySource openReplaySource(ReplayFormat format, const std::vector<std::string>& paths,
                              const ReplaySourceOptions& options);

}  // namespace rmap::cli
