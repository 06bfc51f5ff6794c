#pragma once
/// @file slam_relations.h
/// Reader of the relation files of the SLAM benchmark of Kümmerle et al.,
/// "On measuring the accuracy of SLAM algorithms", Autonomous Robots 27(4),
/// 2009: manually verified relative motions between pairs of scans.
///
/// One relation per line: `t1 t2 x y z roll pitch yaw` — the motion from the
/// pose at timestamp t1 to the pose at t2, expressed in the frame of t1
/// (metres, radians). The files are planar (z = roll = pitch = 0); a nonzero
/// z, roll or pitch is rejected rather than silently dropped. Blank lines and
/// '#' comments are skipped.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "slam2d/pose2.h"

namespace rmap::datasets {

struct SlamRelation {
  int64_t from_stamp_ns = 0;  ///< t1, parsed exactly (parseCarmenStampNs)
  int64_t to_stamp_ns = 0;    ///< t2
  slam2d::Pose2 motion;       ///< pose(t1)⁻¹ · pose(t2)
  size_t line = 0;
};

/// @throws std::runtime_error "<source>:<line>: ..." for a wrong field
///         count, a malformed or non-finite number, or a non-planar relation
std::vector<SlamRelation> parseSlamRelations(std::string_view text, const std::string& source);

/// Reads a relation file (plain, gzip or bzip2).
std::vector<SlamRelation> readSlamRelations(const std::string& path);

}  // namespace rmap::datasets
