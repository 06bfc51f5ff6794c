#pragma once
/// @file map_server_yaml.h
/// The ROS map_server pair `rmap export --format pgm` writes: FILE (the PGM)
/// and a YAML beside it whose `image:` names FILE.

#include <filesystem>
#include <string>

namespace rmap::cli {

/// FILE with its extension replaced by `.yaml` (`.yaml` appended when it has none).
std::filesystem::path yamlPathFor(const std::filesystem::path& pgm_path);

/// The YAML with its `image:` line set to `image` (added first when absent).
std::string withImage(const std::string& yaml, const std::string& image);

/// The "<epoch>-<version>" of a 2D product's ETag ("<epoch>-<version>-<product>",
/// docs/API.md §7a.4): products drawn from the same grid share it. Empty when malformed.
std::string layerVersionOf(const std::string& etag);

}  // namespace rmap::cli
