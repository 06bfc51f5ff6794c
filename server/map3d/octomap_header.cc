#include "map3d/octomap_header.h"

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <system_error>

namespace rmap::map3d {
namespace {

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }

/// Whitespace-separated tokens over the bytes, with line skipping.
class HeaderReader {
 public:
  explicit HeaderReader(std::string_view bytes) : bytes_(bytes) {}

  /// Next whitespace-delimited token, empty at the end of the input.
  std::string_view token() {
    while (pos_ < bytes_.size() && isSpace(bytes_[pos_])) ++pos_;
    const size_t start = pos_;
    while (pos_ < bytes_.size() && !isSpace(bytes_[pos_])) ++pos_;
    return bytes_.substr(start, pos_ - start);
  }

  void skipLine() {
    const size_t nl = bytes_.find('\n', pos_);
    pos_ = nl == std::string_view::npos ? bytes_.size() : nl + 1;
  }

  size_t position() const { return pos_; }

 private:
  std::string_view bytes_;
  size_t pos_ = 0;
};

template <typename T>
bool parseNumber(std::string_view text, T& value) {
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && end == text.data() + text.size();
}

}  // namespace

OctreeHeader readOctreeHeader(std::string_view bytes, std::string_view magic, const std::string& format) {
  const auto fail = [&](const std::string& what) { return std::runtime_error(format + ": " + what); };
  if (bytes.substr(0, magic.size()) != magic) {
    throw fail("first line does not start with \"" + std::string(magic) + "\"");
  }
  HeaderReader in(bytes);
  in.skipLine();
  bool have_res = false, have_size = false;
  OctreeHeader h;
  for (;;) {
    const std::string_view t = in.token();
    if (t.empty()) throw fail("header ends before the \"data\" line");
    if (t == "data") {
      in.skipLine();
      break;
    }
    if (t.front() == '#') {
      in.skipLine();
    } else if (t == "id") {
      h.id = in.token();
    } else if (t == "res") {
      const std::string_view v = in.token();
      if (!parseNumber(v, h.resolution_m)) throw fail("bad res value \"" + std::string(v) + "\"");
      have_res = true;
    } else if (t == "size") {
      const std::string_view v = in.token();
      if (!parseNumber(v, h.size)) throw fail("bad size value \"" + std::string(v) + "\"");
      have_size = true;
    } else {
      in.skipLine();  // OctoMap warns about unknown keywords and skips them
    }
  }
  if (!have_res) throw fail("header has no res");
  if (!(h.resolution_m > 0.0) || !std::isfinite(h.resolution_m)) throw fail("res must be finite and > 0");
  if (!have_size) throw fail("header has no size");
  h.data_offset = in.position();
  return h;
}

bool isEmptyTree(const OctreeHeader& header, std::string_view data, const std::string& format) {
  if (header.size != 0) return false;
  if (!data.empty()) {
    throw std::runtime_error(format + ": " + std::to_string(data.size()) + " bytes of data after a header with size 0");
  }
  return true;
}

void checkTreeEnd(const OctreeHeader& header, std::string_view data, size_t bytes_read, uint64_t nodes_read,
                  const std::string& format) {
  if (bytes_read != data.size()) {
    throw std::runtime_error(format + ": " + std::to_string(data.size() - bytes_read) + " trailing bytes after the tree");
  }
  if (nodes_read != header.size) {
    throw std::runtime_error(format + ": tree has " + std::to_string(nodes_read) + " nodes but the header says size " +
                             std::to_string(header.size));
  }
}

}  // namespace rmap::map3d
