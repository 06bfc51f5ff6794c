#pragma once
/// @file commands.h
/// The `rmap` subcommands. Each add*Command registers a subcommand with its
/// options on `app`; when that subcommand is chosen, its callback runs the
/// command and stores 0 (success) or 1 (failure, message on stderr) in `exit_code`.

#include <CLI/CLI.hpp>

namespace rmap::cli {

}  // namespace rmap::cli
