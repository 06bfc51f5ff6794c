#pragma once
/// @file text_fields.h
/// Line and number scanning shared by the text dataset readers, with errors
/// that name the source and the line.

#include <algorithm>
#include <cstddef>
#include <string>
#include <string_view>

namespace rmap::datasets {

/// The lines of a text: split on '\n', a trailing '\r' removed, numbered from 1.
class TextLines {
 public:
  explicit TextLines(std::string_view text) : text_(text) {}

  /// Next line without its terminator; false after the last one.
  bool next(std::string_view& line);

  /// 1-based number of the line last returned by next().
  size_t number() const { return number_; }

  /// Offset of the first byte after the line last returned and its '\n'.
  size_t offset() const { return std::min(pos_, text_.size()); }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  size_t number_ = 0;
};

/// The line up to its first '#' (the rest is a comment).
std::string_view stripComment(std::string_view line);

/// Splits a line on spaces and tabs. Stores at most `max` fields and returns
/// how many there are, so a result above `max` means too many fields.
size_t splitFields(std::string_view line, std::string_view* fields, size_t max);

/// Throws std::runtime_error("<source>:<line>: <problem>").
[[noreturn]] void throwAt(const std::string& source, size_t line, const std::string& problem);

/// Parses a whole field as a decimal number (optional leading '+'; "nan" and
/// "inf" are accepted, callers decide about non-finite values).
/// @throws std::runtime_error naming source, line and field when malformed
double parseNumber(std::string_view field, const std::string& source, size_t line);

}  // namespace rmap::datasets
