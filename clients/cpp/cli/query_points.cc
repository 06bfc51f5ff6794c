#include "cli/query_points.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <system_error>

namespace rmap::cli {

namespace {

bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && isBlank(s.front())) s.remove_prefix(1);
  while (!s.empty() && isBlank(s.back())) s.remove_suffix(1);
  return s;
}

/// Splits at `separators`, dropping empty fields (so runs of spaces are one separator).
std::vector<std::string_view> fields(std::string_view s, std::string_view separators) {
  std::vector<std::string_view> out;
  size_t begin = 0;
  while (begin <= s.size()) {
    const size_t end = std::min(s.find_first_of(separators, begin), s.size());
    if (const std::string_view f = trim(s.substr(begin, end - begin)); !f.empty()) out.push_back(f);
    begin = end + 1;
  }
  return out;
}

bool parseFinite(std::string_view text, double& value) {
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && end == text.data() + text.size() && std::isfinite(value);
}

}  // namespace

std::vector<double> parseNumbers(std::string_view text, size_t count, const std::string& what) {
  const std::vector<std::string_view> parts = fields(text, ",");
  std::vector<double> out(parts.size());
  bool ok = parts.size() == count && std::count(text.begin(), text.end(), ',') == static_cast<long>(count - 1);
  for (size_t i = 0; ok && i < parts.size(); ++i) ok = parseFinite(parts[i], out[i]);
  if (!ok) {
    throw std::invalid_argument(what + " must be " + std::to_string(count) + " finite numbers separated by commas, not '" +
                                std::string(text) + "'");
  }
  return out;
}

std::vector<Eigen::Vector3d> parsePointLines(std::string_view text, const std::string& source) {
  std::vector<Eigen::Vector3d> points;
  size_t line_number = 0;
  for (size_t begin = 0; begin < text.size();) {
    const size_t end = std::min(text.find('\n', begin), text.size());
    const std::string_view line = trim(text.substr(begin, end - begin));
    begin = end + 1;
    ++line_number;
    if (line.empty() || line.front() == '#') continue;
    const std::vector<std::string_view> parts = fields(line, line.find(',') != std::string_view::npos ? "," : " \t");
    Eigen::Vector3d p;
    bool ok = parts.size() == 3;
    for (int a = 0; ok && a < 3; ++a) ok = parseFinite(parts[a], p[a]);
    if (!ok) {
      throw std::invalid_argument(source + ":" + std::to_string(line_number) +
                                  ": expected three finite numbers 'x y z' or 'x,y,z', got '" + std::string(line) + "'");
    }
    points.push_back(p);
  }
  return points;
}

}  // namespace rmap::cli
