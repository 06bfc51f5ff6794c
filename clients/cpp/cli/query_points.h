#pragma once
/// @file query_points.h
/// Points and boxes as `rmap query` reads them: "X,Y,Z" and
/// "MINX,MINY,MINZ,MAXX,MAXY,MAXZ" on the command line (metres, map frame),
/// and batch files of one point per line.

#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

namespace rmap::cli {

/// `count` finite numbers separated by commas (spaces around them allowed).
/// @throws std::invalid_argument naming `what` and the text
std::vector<double> parseNumbers(std::string_view text, size_t count, const std::string& what);

/// A batch file: one point per line as "x y z" or "x,y,z" (metres); blank
/// lines and lines starting with '#' are skipped.
/// @param source  named in messages (the path)
/// @throws std::invalid_argument "<source>:<line>: …" for a line that is not three finite numbers
std::vector<Eigen::Vector3d> parsePointLines(std::string_view text, const std::string& source);

}  // namespace rmap::cli
