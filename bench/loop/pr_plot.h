#pragma once
/// @file pr_plot.h
/// Precision–recall curves drawn with OpenCV (recall on x, precision on y,
/// both 0..1), one colour per tolerance, for a PNG next to the CSVs.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "loop/loop_scoring.h"

namespace rmap::bench {

/// A BGR image of `width`×`height` px with axes, grid, the curves and a legend.
cv::Mat drawPrCurves(const std::vector<PrCurve>& curves, const std::string& title, int width = 720, int height = 540);

}  // namespace rmap::bench
