#pragma once
/// @file dataset_test_support.h
/// What the readers' tests share: the check for bad input (parsing must throw
/// std::runtime_error whose message says what is wrong), binary input made by
/// hand, and point comparisons.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cstring>
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

/// Appends the bytes of `v` to `out`, in the host's (little-endian) order or reversed.
template <class T>
void appendBinary(std::string& out, T v, bool big_endian = false) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof v);
  if (big_endian) std::reverse(b, b + sizeof b);
  out.append(b, sizeof b);
}

/// Expects `p` at (x, y, z) within `tolerance` per axis.
inline void expectPoint(const Eigen::Vector3f& p, double x, double y, double z, double tolerance = 1e-6) {
  EXPECT_NEAR(p.x(), x, tolerance);
  EXPECT_NEAR(p.y(), y, tolerance);
  EXPECT_NEAR(p.z(), z, tolerance);
}

}  // namespace rmap::datasets
