#pragma once
/// @file rmap_cli.h
/// Runs the real `rmap` binary (rmapCliPath()) for end-to-end tests and
/// captures what it printed.

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "rmapd_process.h"

namespace rmap::testing {

struct CliRun {
  int exit_code = -1;
  std::string out;  ///< stdout
  std::string err;  ///< stderr
};

inline std::string fileText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return std::move(text).str();
}

/// `rmap <args>` (arguments already quoted for the shell), output kept in `scratch`.
inline CliRun runRmap(const std::string& args, const std::filesystem::path& scratch) {
  const std::filesystem::path out = scratch / "rmap.out", err = scratch / "rmap.err";
  const std::string command =
      std::string(rmapCliPath()) + " " + args + " > '" + out.string() + "' 2> '" + err.string() + "'";
  const int status = std::system(command.c_str());
  CliRun run;
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.out = fileText(out);
  run.err = fileText(err);
  return run;
}

}  // namespace rmap::testing
