#pragma once
/// @file commands.h
/// The `rmap` subcommands. Each add*Command registers a subcommand with its
/// options on `app`; when that subcommand is chosen, its callback runs the
/// command and stores 0 (success) or 1 (failure, message on stderr) in `exit_code`.

#include <CLI/CLI.hpp>

namespace rmap::cli {

/// `rmap replay`: datasets on disk streamed to rmapd as one robot (replay_command.cc).
void addReplayCommand(CLI::App& app, int& exit_code);
/// `rmap query`: occupancy at a point, in a box, or for a file of points (docs/CLI.md).
void addQueryCommand(CLI::App& app, int& exit_code);
/// `rmap export`: a map as OctoMap .bt, PLY, map_server PGM + YAML or reflectivity PNG.
void addExportCommand(CLI::App& app, int& exit_code);
/// `rmap import`: an OctoMap .bt or .ot into a map.
void addImportCommand(CLI::App& app, int& exit_code);

}  // namespace rmap::cli
