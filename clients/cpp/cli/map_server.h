#pragma once
/// @file map_server.h
/// What the rmap CLI asks of rmapd's HTTP API, shared by its map commands
/// (query, export, import): the server, map and token options, the client,
/// and server errors turned into messages.

#include <CLI/CLI.hpp>

#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>

#include "client/http_client.h"

namespace rmap::cli {

/// A command that failed; the message is printed as `rmap <command>: <message>`.
class CommandError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// --server, --map, --token, --ca-file and --timeout-s of a map command.
struct MapServerOptions {
  std::string server_url;  ///< http://HOST:PORT or https://HOST:PORT
  std::string map;
  std::string token;  ///< bearer token; empty in loopback-only mode
  std::string ca_file;  ///< https://: PEM CA certificates to verify rmapd against; empty = the system's
  double timeout_s = 30.0;

  /// Adds the options to `command`; `timeout_s` is the default kept.
  void addTo(CLI::App& command);
  std::unique_ptr<client::HttpClient> connect() const;
  /// "/v1/maps/<map>" followed by `suffix`.
  std::string mapPath(const std::string& suffix = {}) const;
};

/// Returns the response when its status is 2xx.
/// @throws CommandError "<what>: HTTP <status> <code>: <message>" with the
///         server's JSON error (docs/API.md §4), or the body when it is not one
client::HttpResponse requireOk(client::HttpResponse response, const std::string& what);

/// Writes `bytes` to `path` through a temporary file beside it, renamed at
/// the end, so a failed export leaves no half-written file.
/// @throws CommandError naming the path
void writeFileAtomically(const std::filesystem::path& path, const std::string& bytes);

/// The whole file. @throws CommandError naming the path
std::string readFile(const std::filesystem::path& path);

/// Runs `command`, printing any exception it throws (CommandError,
/// client::ClientError, bad input) as `rmap <name>: <message>` on stderr.
/// @return the exit code (0 or 1)
int runCommand(const std::string& name, const std::function<void()>& command);

}  // namespace rmap::cli
