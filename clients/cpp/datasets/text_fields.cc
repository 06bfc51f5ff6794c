#include "datasets/text_fields.h"

#include <charconv>
#include <stdexcept>
#include <system_error>

namespace rmap::datasets {

bool TextLines::next(std::string_view& line) {
  if (pos_ >= text_.size()) return false;
  const size_t nl = text_.find('\n', pos_);
  const size_t end = nl == std::string_view::npos ? text_.size() : nl;
  line = text_.substr(pos_, end - pos_);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  pos_ = end + 1;
  ++number_;
  return true;
}

std::string_view stripComment(std::string_view line) { return line.substr(0, line.find('#')); }

size_t splitFields(std::string_view line, std::string_view* fields, size_t max) {
  size_t count = 0;
  size_t i = 0;
  while (true) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    if (i == line.size()) return count;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (count < max) fields[count] = line.substr(start, i - start);
    ++count;
  }
}

void throwAt(const std::string& source, size_t line, const std::string& problem) {
  throw std::runtime_error(source + ":" + std::to_string(line) + ": " + problem);
}

double parseNumber(std::string_view field, const std::string& source, size_t line) {
  // from_chars rejects the leading '+' that printf-style writers may emit.
  std::string_view digits = field;
  if (digits.size() > 1 && digits.front() == '+' && digits[1] != '-') digits.remove_prefix(1);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (ec == std::errc::result_out_of_range) throwAt(source, line, "number out of range \"" + std::string(field) + "\"");
  if (ec != std::errc() || end != digits.data() + digits.size()) {
    throwAt(source, line, "malformed number \"" + std::string(field) + "\"");
  }
  return value;
}

}  // namespace rmap::datasets
