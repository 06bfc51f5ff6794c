#pragma once
/// @file carmen_log.h
/// Reader of CARMEN text logs (the format of the Radish / Freiburg 2D laser
/// datasets), giving scans as slam2d::LaserScan with the poses and odometry
/// the log carries.
///
/// Messages read (one per line, fields separated by spaces):
/// - `ODOM x y theta tv rv accel ipc_timestamp host logger_timestamp`
/// - `FLASER n r_1 … r_n x y theta odom_x odom_y odom_theta ipc_timestamp host logger_timestamp`:
///   `x y theta` is the laser pose, the odom fields the robot pose (both raw
///   odometry in a raw log, SLAM-corrected poses in a corrected log).
///   The message carries no angles; as CARMEN's own reader
///   (carmen_laser_guess_fov / _angle_increment) does, the first beam is at
///   −90° (the robot's right) and the beams are spaced 180°/(n − 1) for odd n,
///   180°/n for even n: an even count is the odd one with its last beam
///   dropped. So n = 181 spans −90°…+90° and n = 180 spans −90°…+89° in 1°
///   steps; n = 361 spans −90°…+90° and n = 360 spans −90°…+89.5° in 0.5° steps.
/// - `ROBOTLASER1 type start_angle fov resolution max_range accuracy remission_mode
///   n r_1 … r_n m [remission_1 … remission_m] laser_x laser_y laser_theta robot_x
///   robot_y robot_theta tv rv forward_safety side_safety turn_axis ipc_timestamp host
///   logger_timestamp`: beam i at start_angle + i·resolution; remissions (m = n,
///   or m = 0 for none) become the scan's intensities.
/// Every other message (PARAM, NEFF, RLASER, SYNC, …), blank lines and lines
/// starting with '#' are skipped and counted.
///
/// Ranges: a reading at or above the no-return range is a no return (+inf),
/// a reading ≤ 0 an error reading (NaN); both are kept as beams so that beam
/// indices and angles stay those of the scanner. For ROBOTLASER1 the
/// no-return range is its max_range field. FLASER carries none and loggers
/// mark "no echo" with the scanner's largest code (81.91 or 81.83 m for SICK
/// LMS in cm mode, 32.767 or 51.1 m in other logs), so unless
/// CarmenReadOptions::flaser_no_return_m is set, it is 99 % of the largest
/// FLASER reading of the log: the pile of no-echo codes and anything within
/// 1 % below them.

#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "slam2d/laser_scan.h"
#include "slam2d/pose2.h"

namespace rmap::datasets {

/// One ODOM message.
struct CarmenOdometry {
  int64_t stamp_ns = 0;       ///< ipc_timestamp
  slam2d::Pose2 pose;         ///< robot pose as logged (m, rad)
  double velocity_mps = 0.0;  ///< tv
  double turn_rate_radps = 0.0;  ///< rv
  size_t line = 0;            ///< 1-based line in the log
};

/// One FLASER or ROBOTLASER1 message.
struct CarmenScan {
  /// stamp_ns = ipc_timestamp; model "FLASER" or "ROBOTLASER1/<type>";
  /// sensor_mount = robot_pose⁻¹ · laser_pose.
  slam2d::LaserScan scan;
  slam2d::Pose2 laser_pose;  ///< as logged: raw odometry or corrected (m, rad)
  slam2d::Pose2 robot_pose;  ///< as logged
  /// How many ODOM messages precede this scan in the file: odometry[k] for
  /// k < odometry_before came earlier, the others later.
  size_t odometry_before = 0;
  size_t line = 0;           ///< 1-based line in the log
};

struct CarmenLog {
  std::vector<CarmenScan> scans;          ///< in file order
  std::vector<CarmenOdometry> odometry;   ///< in file order
  std::map<std::string, size_t> skipped;  ///< message name → lines skipped
  float flaser_no_return_m = 0.0f;        ///< the no-return range used for FLASER (0 without FLASER)
};

struct CarmenReadOptions {
  /// FLASER readings at or above this are no returns (m); ≤ 0: derived from
  /// the log as described in the file comment.
  float flaser_no_return_m = 0.0f;
};

/// Parses the text of a CARMEN log.
/// @param source  name used in error messages (usually the path)
/// @throws std::runtime_error "<source>:<line>: ..." for a read message with
///         a wrong field count, a malformed or non-finite number, a beam
///         count < 2, or a ROBOTLASER1 remission count other than 0 or n
CarmenLog parseCarmenLog(std::string_view text, const std::string& source, const CarmenReadOptions& options = {});

/// Reads a log file, plain, gzip or bzip2 (see readFileMaybeCompressed).
CarmenLog readCarmenLog(const std::string& path, const CarmenReadOptions& options = {});

/// Parses a CARMEN timestamp (seconds) to nanoseconds. Plain decimals (as
/// "976052857.337284") are converted exactly, without going through a
/// double, so stamps written with the same digits in different files compare
/// equal; other number forms ("-0.042", "1.13486e+09": some corrected logs
/// print stamps so, rounded to 6 digits) are read as a double.
/// @throws std::runtime_error naming source and line when malformed, not
///         finite or beyond ±9e9 s
int64_t parseCarmenStampNs(std::string_view field, const std::string& source, size_t line);

/// Whether the log's odometry restarts from every scan's pose: the first
/// ODOM after a scan equals that scan's robot pose (within 1e-6 m and rad)
/// for at least 90 % of the scans followed by one. That is how corrected
/// logs are written; in raw logs odometry runs on, so only stops match.
bool odometryRestartsAtScans(const CarmenLog& log);

/// Robot odometry poses at the scans, in an odometry frame starting at the
/// origin at the first scan, for a log whose ODOM lines restart at each
/// scan's (corrected) pose: the increment from scan k to scan k + 1 is
/// robot_pose_k⁻¹ · (last ODOM before scan k + 1), which holds only the
/// wheel motion and none of the correction. The increment stops at that last
/// ODOM, so it misses the motion until scan k + 1 itself (at most one
/// odometry period). Scan k + 1 gets none (std::nullopt) when no ODOM
/// follows scan k's restart before it: its motion is unknown, not zero
/// (orebro's log restarts after every scan and logs nothing else).
std::vector<std::optional<slam2d::Pose2>> odometryFromOdomIncrements(const CarmenLog& log);

}  // namespace rmap::datasets
