#pragma once
/// @file replay_format.h
/// The dataset formats `rmap replay` reads, told apart by file names or
/// folder contents, and the robot id a replay takes from its files.

#include <string>
#include <vector>

namespace rmap::cli {

enum class ReplayFormat { kCarmen, kOctomapGraph, kXyzText, kVelodyneBin, kPly, kPcd, kUos3dtk, kImages };

/// The names --format takes: carmen, graph, xyz, kitti, ply, pcd, 3dtk, images.
const std::vector<std::string>& replayFormatNames();
const char* toString(ReplayFormat format);
/// @throws std::invalid_argument for another name
ReplayFormat parseReplayFormat(const std::string& name);

/// The format of FILE arguments from their names (compression suffixes
/// .gz/.bz2 looked through: .clf/.log CARMEN, .graph, .dat/.xyz/.txt text
/// clouds, .bin velodyne, .ply, .pcd, .png/.jpg/.jpeg images) or, for
/// folders, from what they hold: a 3DTK folder has scan000.3d; otherwise the
/// one kind of frame file it holds (.bin, .ply, .pcd or images).
/// @throws std::runtime_error naming the file when no format fits or files disagree
ReplayFormat detectReplayFormat(const std::vector<std::string>& paths);

/// Whether `path` is a frame file of `format` (by its name).
bool isFrameFile(ReplayFormat format, const std::string& path);

/// The robot id a replay uses by default: the first path's name without
/// directories and extensions (`intel.log.gz` → `intel`), characters outside
/// [A-Za-z0-9._-] replaced by '-', at most 64 characters; "replay" if empty.
std::string defaultRobotId(const std::string& path);

}  // namespace rmap::cli
