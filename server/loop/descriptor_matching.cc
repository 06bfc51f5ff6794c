#include "loop/descriptor_matching.h"

#include <climits>
#include <opencv2/core/hal/hal.hpp>

namespace rmap::loop {

namespace {

struct Nearest {
  int index = -1;
  int first = INT_MAX;
  int second = INT_MAX;
};

std::vector<Nearest> nearestRows(const cv::Mat& a, const cv::Mat& b) {
  std::vector<Nearest> out(a.rows);
  for (int i = 0; i < a.rows; ++i) {
    const uchar* ra = a.ptr<uchar>(i);
    Nearest& n = out[i];
    for (int j = 0; j < b.rows; ++j) {
      const int d = cv::hal::normHamming(ra, b.ptr<uchar>(j), a.cols);
      if (d < n.first) {
        n.second = n.first;
        n.first = d, n.index = j;
      } else if (d < n.second) {
        n.second = d;
      }
    }
  }
  return out;
}

}  // namespace

std::vector<std::pair<int, int>> mutualMatches(const cv::Mat& a, const cv::Mat& b, int max_bits, double ratio) {
  std::vector<std::pair<int, int>> out;
  if (a.rows == 0 || b.rows == 0) return out;
  const std::vector<Nearest> ab = nearestRows(a, b);
  const std::vector<Nearest> ba = nearestRows(b, a);
  for (int i = 0; i < a.rows; ++i) {
    const Nearest& n = ab[i];
    if (n.index < 0 || n.first > max_bits || ba[n.index].index != i) continue;
    if (n.second != INT_MAX && n.first >= ratio * n.second) continue;
    out.emplace_back(i, n.index);
  }
  return out;
}

}  // namespace rmap::loop
