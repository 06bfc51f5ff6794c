#pragma once
/// @file xyz_text.h
/// Reader of OctoMap's plain-text scan logs (`scan.dat`, the input of
/// ScanGraph::readPlainASCII): one point `x y z` per line, in metres.
///
/// A line `NODE x y z roll pitch yaw` starts a new scan taken from that pose
/// (metres; radians, rotation Rz(yaw)·Ry(pitch)·Rx(roll) as octomath::Pose6D);
/// the points after it are in that sensor's frame and are returned in the
/// world frame. Points before any NODE line form a scan with the sensor at the
/// origin, so a file without NODE lines is one scan (OctoMap's own scan.dat
/// has none). Blank lines and everything after '#' are ignored.

#include <string>
#include <string_view>
#include <vector>

#include "datasets/point_scan.h"

namespace rmap::datasets {

/// Parses the text. Scans started by NODE lines are kept even when empty;
/// the implicit first scan only when it has points.
/// @param source  name used in error messages (usually the path)
/// @throws std::runtime_error "<source>:<line>: ..." for a malformed or
///         non-finite number or a wrong number of fields
std::vector<PointScan> parseXyzText(std::string_view text, const std::string& source);

/// Reads a file, optionally .gz/.bz2 compressed, with parseXyzText.
std::vector<PointScan> readXyzText(const std::string& path);

}  // namespace rmap::datasets
