#include "cli/replay_format.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <optional>
#include <stdexcept>

#include "datasets/camera_image_file.h"

namespace rmap::cli {
namespace {

namespace fs = std::filesystem;

const std::map<std::string, ReplayFormat>& formatsByName() {
  static const std::map<std::string, ReplayFormat> kNames = {
      {"carmen", ReplayFormat::kCarmen}, {"graph", ReplayFormat::kOctomapGraph}, {"xyz", ReplayFormat::kXyzText},
      {"kitti", ReplayFormat::kVelodyneBin}, {"ply", ReplayFormat::kPly}, {"pcd", ReplayFormat::kPcd},
      {"3dtk", ReplayFormat::kUos3dtk}, {"images", ReplayFormat::kImages}};
  return kNames;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

/// The extension that tells the format: ".log" for "x.log.gz".
std::string formatExtension(const std::string& path) {
  fs::path p = fs::path(path).filename();
  std::string ext = lower(p.extension().string());
  if (ext == ".gz" || ext == ".bz2") ext = lower(p.stem().extension().string());
  return ext;
}

std::optional<ReplayFormat> formatOfFile(const std::string& path) {
  if (datasets::isImageFileName(path)) return ReplayFormat::kImages;
  static const std::map<std::string, ReplayFormat> kExtensions = {
      {".clf", ReplayFormat::kCarmen}, {".log", ReplayFormat::kCarmen},  {".graph", ReplayFormat::kOctomapGraph},
      {".dat", ReplayFormat::kXyzText}, {".xyz", ReplayFormat::kXyzText}, {".txt", ReplayFormat::kXyzText},
      {".bin", ReplayFormat::kVelodyneBin}, {".ply", ReplayFormat::kPly}, {".pcd", ReplayFormat::kPcd}};
  const auto it = kExtensions.find(formatExtension(path));
  if (it == kExtensions.end()) return std::nullopt;
  return it->second;
}


ReplayFormat formatOfFolder(const std::string& dir) {
  if (fs::exists(fs::path(dir) / "scan000.3d")) return ReplayFormat::kUos3dtk;
  std::optional<ReplayFormat> found;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file()) continue;
    const std::optional<ReplayFormat> f = formatOfFile(entry.path().string());
    if (!f || (*f != ReplayFormat::kVelodyneBin && *f != ReplayFormat::kPly && *f != ReplayFormat::kPcd &&
               *f != ReplayFormat::kImages)) {
      continue;
    }
    if (found && *found != *f) {
      throw std::runtime_error(dir + ": holds both " + toString(*found) + " and " + toString(*f) +
                               " frames; pick one with --format");
    }
    found = f;
  }
  if (ec) throw std::runtime_error(dir + ": cannot list: " + ec.message());
  if (!found) throw std::runtime_error(dir + ": no scan000.3d, .bin, .ply, .pcd or image file in it");
  return *found;
}

}  // namespace

bool isFrameFile(ReplayFormat format, const std::string& path) {
  if (format == ReplayFormat::kImages) return datasets::isImageFileName(path);
  const std::optional<ReplayFormat> f = formatOfFile(path);
  return f && *f == format;
}

const std::vector<std::string>& replayFormatNames() {
  static const std::vector<std::string> kNames = [] {
    std::vector<std::string> names;
    for (const auto& [name, format] : formatsByName()) names.push_back(name);
    return names;
  }();
  return kNames;
}

const char* toString(ReplayFormat format) {
  switch (format) {
    case ReplayFormat::kCarmen: return "carmen";
    case ReplayFormat::kOctomapGraph: return "graph";
    case ReplayFormat::kXyzText: return "xyz";
    case ReplayFormat::kVelodyneBin: return "kitti";
    case ReplayFormat::kPly: return "ply";
    case ReplayFormat::kPcd: return "pcd";
    case ReplayFormat::kUos3dtk: return "3dtk";
    case ReplayFormat::kImages: return "images";
  }
  return "?";
}

ReplayFormat parseReplayFormat(const std::string& name) {
  const auto it = formatsByName().find(name);
  if (it == formatsByName().end()) throw std::invalid_argument("unknown format '" + name + "'");
  return it->second;
}

ReplayFormat detectReplayFormat(const std::vector<std::string>& paths) {
  if (paths.empty()) throw std::runtime_error("no file to replay");
  std::optional<ReplayFormat> format;
  for (const std::string& path : paths) {
    std::optional<ReplayFormat> f;
    if (fs::is_directory(path)) {
      f = formatOfFolder(path);
    } else if (!fs::exists(path)) {
      throw std::runtime_error(path + ": no such file");
    } else {
      f = formatOfFile(path);
      if (!f && formatExtension(path) == ".3d") {
        throw std::runtime_error(path + ": give the 3DTK folder (holding scan000.3d, .pose or .frames), not a scan");
      }
      if (!f) throw std::runtime_error(path + ": unknown format (by its name); pick one with --format");
    }
    if (format && *format != *f) {
      throw std::runtime_error(path + ": is " + std::string(toString(*f)) + " but " + paths[0] + " is " +
                               toString(*format) + "; one format per replay");
    }
    format = f;
  }
  return *format;
}

std::string defaultRobotId(const std::string& path) {
  std::string name = fs::path(path).lexically_normal().filename().string();
  if (name.empty()) name = fs::path(path).lexically_normal().parent_path().filename().string();
  const size_t dot = name.find('.');
  if (dot != std::string::npos) name.resize(dot);
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' && c != '-') c = '-';
  }
  if (name.size() > 64) name.resize(64);
  return name.empty() ? "replay" : name;
}

}  // namespace rmap::cli
