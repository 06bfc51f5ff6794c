#pragma once
/// @file static_files.h
/// The web viewer's files, served from a web root directory without
/// authentication (docs/API.md §6.2). Only this URL layout is served:
///   /, /index.html             → <web_root>/index.html
///   /app/<path>                → <web_root>/app/<path>
///   /node_modules/three/build/<path>, /node_modules/three/examples/jsm/<path>
///                              → the same path under <web_root>
/// Files are read per request (no cache: they are small and the page cache
/// holds them); a file's canonical path must stay inside its directory, so
/// neither `..` nor a symlink reaches anything else.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "net/service.h"

namespace rmap::app {

class StaticFiles {
 public:
  /// @param web_root  the viewer's directory; relative paths are taken from the working directory
  explicit StaticFiles(const std::filesystem::path& web_root);

  /// Answers a request whose decoded path is `segments` when it is one of the
  /// static routes; nullopt for any other path.
  /// @throws ApiError 405 for methods other than GET and HEAD, 400 for a
  ///         segment that is `.`, `..` or holds `/` or NUL, 404 for anything
  ///         not served, 503 on the index when the viewer is not installed
  std::optional<net::Response> serve(const net::Request& request, const std::vector<std::string>& segments) const;

  const std::filesystem::path& root() const { return root_; }

 private:
  std::filesystem::path root_;
};

/// The first file the viewer needs that `web_root` lacks (index.html, then
/// three's module build, which `npm ci --prefix web` installs), or nullopt
/// when the viewer is installed.
std::optional<std::filesystem::path> missingViewerFile(const std::filesystem::path& web_root);

/// Content-Type of a served file, by its (case-insensitive) extension;
/// application/octet-stream for unknown ones.
std::string_view contentTypeFor(const std::filesystem::path& file);

/// Content-Security-Policy of an HTML page: everything from this server only,
/// and of inline scripts only the page's import maps, allowed by their
/// SHA-256 hashes (computed from `html` as the browser will).
std::string contentSecurityPolicy(std::string_view html);

}  // namespace rmap::app
