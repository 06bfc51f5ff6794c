#include "cli/map_server_yaml.h"

#include <sstream>

namespace rmap::cli {

std::filesystem::path yamlPathFor(const std::filesystem::path& pgm_path) {
  std::filesystem::path yaml = pgm_path;
  return yaml.replace_extension(".yaml");
}

std::string withImage(const std::string& yaml, const std::string& image) {
  std::istringstream in(yaml);
  std::string out;
  bool replaced = false;
  for (std::string line; std::getline(in, line);) {
    if (!replaced && line.rfind("image:", 0) == 0) {
      line = "image: " + image;
      replaced = true;
    }
    out += line + "\n";
  }
  return replaced ? out : "image: " + image + "\n" + out;
}

std::string layerVersionOf(const std::string& etag) {
  const size_t first = etag.find('-');
  const size_t second = first == std::string::npos ? std::string::npos : etag.find('-', first + 1);
  if (etag.size() < 2 || etag.front() != '"' || second == std::string::npos) return {};
  return etag.substr(1, second - 1);
}

}  // namespace rmap::cli
