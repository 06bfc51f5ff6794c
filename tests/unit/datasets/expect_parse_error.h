#pragma once
/// @file expect_parse_error.h
/// The readers' shared check for bad input: parsing must throw
/// std::runtime_error, and its message must say what is wrong.

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace rmap::datasets {

/// Expects `parse(content)` to throw a std::runtime_error whose message holds `part`.
template <class Parse>
void expectParseError(Parse&& parse, const std::string& content, const std::string& part) {
  try {
    parse(content);
    ADD_FAILURE() << "accepted: " << content;
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

}  // namespace rmap::datasets
