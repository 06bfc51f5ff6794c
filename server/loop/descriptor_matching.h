#pragma once
/// @file descriptor_matching.h
/// Brute-force matching of two sets of binary descriptors: pairs that are
/// each other's nearest neighbour by Hamming distance, within a distance
/// bound, and pass the ratio test against the second nearest.
/// Cost: rows(a) · rows(b) Hamming distances.

#include <opencv2/core.hpp>
#include <utility>
#include <vector>

namespace rmap::loop {

/// (row of a, row of b) pairs; `a` and `b` are CV_8U of the same width.
/// @param max_bits  largest accepted distance
/// @param ratio     nearest / second-nearest distance (both directions' second nearest of the a row) must be below this
std::vector<std::pair<int, int>> mutualMatches(const cv::Mat& a, const cv::Mat& b, int max_bits, double ratio);

}  // namespace rmap::loop
