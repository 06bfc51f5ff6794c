#pragma once
/// @file angles.h
/// Degrees, for the slam2d tests that state angles in them.

#include <numbers>

namespace rmap::slam2d {

inline constexpr double kDeg = std::numbers::pi / 180.0;  ///< radians per degree

}  // namespace rmap::slam2d
