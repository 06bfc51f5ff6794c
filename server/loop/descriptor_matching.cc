#include "loop/descriptor_matching.h"

#include <climits>

#include "loop/binary_descriptor.h"

namespace rmap::loop {

std::vector<std::pair<int, int>> mutualMatches(const cv::Mat& a, const cv::Mat& b, int max_bits, double ratio) {
  std::vector<std::pair<int, int>> out;
  if (a.rows == 0 || b.rows == 0) return out;
  const int blocks = descriptorBlocks(a.cols);
  auto pack = [&](const cv::Mat& m) {
    std::vector<uint64_t> p(static_cast<size_t>(m.rows) * blocks);
    for (int i = 0; i < m.rows; ++i) packDescriptor(m.ptr<uint8_t>(i), m.cols, p.data() + static_cast<size_t>(i) * blocks);
    return p;
  };
  const std::vector<uint64_t> pa = pack(a), pb = pack(b);
  // One pass over the distance matrix: each row's two nearest columns, each column's nearest row.
  std::vector<int> row_best(a.rows, -1), row_first(a.rows, INT_MAX), row_second(a.rows, INT_MAX);
  std::vector<int> col_best(b.rows, -1), col_first(b.rows, INT_MAX);
  for (int i = 0; i < a.rows; ++i) {
    const uint64_t* da = pa.data() + static_cast<size_t>(i) * blocks;
    int best = -1, first = INT_MAX, second = INT_MAX;
    for (int j = 0; j < b.rows; ++j) {
      const int d = hammingDistance(da, pb.data() + static_cast<size_t>(j) * blocks, blocks);
      if (d < first) {
        second = first;
        first = d, best = j;
      } else if (d < second) {
        second = d;
      }
      if (d < col_first[j]) col_first[j] = d, col_best[j] = i;
    }
    row_best[i] = best, row_first[i] = first, row_second[i] = second;
  }
  for (int i = 0; i < a.rows; ++i) {
    const int j = row_best[i];
    if (j < 0 || row_first[i] > max_bits || col_best[j] != i) continue;
    if (row_second[i] != INT_MAX && row_first[i] >= ratio * row_second[i]) continue;
    out.emplace_back(i, j);
  }
  return out;
}

}  // namespace rmap::loop
