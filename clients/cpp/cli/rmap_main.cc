// rmap: the command line for rmapd users. Each subcommand lives in its own file
// and registers itself on the app here (see commands.h).
//
//   rmap replay --server ws://HOST:PORT --map NAME FILE...
//   rmap query  --server http://HOST:PORT --map NAME (--point X,Y,Z | --box ... | --batch FILE)
//   rmap export --server http://HOST:PORT --map NAME --format bt|ply|pgm|reflectivity --output FILE
//   rmap import --server http://HOST:PORT --map NAME FILE.bt|FILE.ot
//
// Exit codes: 0 success, 1 the command failed (message on stderr), 2 bad arguments.

#include <CLI/CLI.hpp>

#include "cli/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"rmap: stream datasets to rmapd, query and export its maps"};
  app.require_subcommand(1, 1);
  int exit_code = 0;
  // One line per subcommand (commands.h).
  rmap::cli::addReplayCommand(app, exit_code);
  rmap::cli::addQueryCommand(app, exit_code);
  rmap::cli::addExportCommand(app, exit_code);
  rmap::cli::addImportCommand(app, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    const int code = app.exit(error);
    return code == 0 ? 0 : 2;
  }
  return exit_code;
}
