#include "loop/descriptor_matching.h"

#include <algorithm>
#include <climits>
#include <cstdint>

#include "loop/binary_descriptor.h"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define RMAP_HAVE_AVX512_POPCNT_KERNEL 1
#endif

namespace rmap::loop {

namespace {

/// Per row of a: its nearest row of b (the first on ties), that distance and
/// the second smallest; per row of b: its nearest row of a (the first on ties)
/// and that distance.
struct Nearest {
  std::vector<int> row_best, row_first, row_second;
  std::vector<int> col_best, col_first;
  Nearest(int rows, int cols)
      : row_best(rows, -1), row_first(rows, INT_MAX), row_second(rows, INT_MAX), col_best(cols, -1), col_first(cols, INT_MAX) {}
};

/// One pass over the distance matrix.
void nearestScalar(const std::vector<uint64_t>& pa, const std::vector<uint64_t>& pb, int blocks, Nearest& n) {
  const int rows = static_cast<int>(n.row_best.size()), cols = static_cast<int>(n.col_best.size());
  for (int i = 0; i < rows; ++i) {
    const uint64_t* da = pa.data() + static_cast<size_t>(i) * blocks;
    int best = -1, first = INT_MAX, second = INT_MAX;
    for (int j = 0; j < cols; ++j) {
      const int d = hammingDistance(da, pb.data() + static_cast<size_t>(j) * blocks, blocks);
      if (d < first) {
        second = first;
        first = d, best = j;
      } else if (d < second) {
        second = d;
      }
      if (d < n.col_first[j]) n.col_first[j] = d, n.col_best[j] = i;
    }
    n.row_best[i] = best, n.row_first[i] = first, n.row_second[i] = second;
  }
}

#ifdef RMAP_HAVE_AVX512_POPCNT_KERNEL
/// The same result with AVX-512 popcounts, eight rows of b at a time: b is
/// transposed block by block so one load holds the same block of eight
/// descriptors. Each lane keeps the running nearest and second nearest of
/// its columns (the first on ties), merged per row of a at its end.
__attribute__((target("avx512f,avx512vpopcntdq"))) void nearestAvx512(const std::vector<uint64_t>& pa,
                                                                      const std::vector<uint64_t>& pb, int blocks,
                                                                      Nearest& n) {
  const int rows = static_cast<int>(n.row_best.size()), cols = static_cast<int>(n.col_best.size());
  const int padded = (cols + 7) & ~7;
  std::vector<uint64_t> columns(static_cast<size_t>(blocks) * padded, 0);
  for (int j = 0; j < cols; ++j)
    for (int k = 0; k < blocks; ++k) columns[static_cast<size_t>(k) * padded + j] = pb[static_cast<size_t>(j) * blocks + k];
  std::vector<int64_t> col_first(padded, INT_MAX), col_best(padded, -1);
  const __m512i lanes = _mm512_set_epi64(7, 6, 5, 4, 3, 2, 1, 0), far = _mm512_set1_epi64(INT_MAX);
  for (int i = 0; i < rows; ++i) {
    const uint64_t* da = pa.data() + static_cast<size_t>(i) * blocks;
    __m512i first = far, second = far, best = _mm512_set1_epi64(-1);
    const __m512i row = _mm512_set1_epi64(i);
    for (int j = 0; j < padded; j += 8) {
      __m512i d = _mm512_setzero_si512();
      for (int k = 0; k < blocks; ++k) {
        const __m512i b = _mm512_loadu_si512(columns.data() + static_cast<size_t>(k) * padded + j);
        d = _mm512_add_epi64(d, _mm512_popcnt_epi64(_mm512_xor_si512(_mm512_set1_epi64(static_cast<long long>(da[k])), b)));
      }
      if (j + 8 > cols) d = _mm512_mask_mov_epi64(d, static_cast<__mmask8>(~((1u << (cols - j)) - 1)), far);
      const __mmask8 nearer = _mm512_cmplt_epi64_mask(d, first);
      second = _mm512_mask_mov_epi64(_mm512_mask_min_epi64(second, 0xFF, second, d), nearer, first);  // (the masked form: GCC 12 warns on the other)
      first = _mm512_mask_mov_epi64(first, nearer, d);
      best = _mm512_mask_mov_epi64(best, nearer, _mm512_add_epi64(lanes, _mm512_set1_epi64(j)));
      const __m512i cf = _mm512_loadu_si512(col_first.data() + j);
      const __mmask8 col_nearer = _mm512_cmplt_epi64_mask(d, cf);
      _mm512_storeu_si512(col_first.data() + j, _mm512_mask_mov_epi64(cf, col_nearer, d));
      _mm512_storeu_si512(col_best.data() + j,
                          _mm512_mask_mov_epi64(_mm512_loadu_si512(col_best.data() + j), col_nearer, row));
    }
    alignas(64) int64_t f[8], s[8], b[8];
    _mm512_store_si512(f, first);
    _mm512_store_si512(s, second);
    _mm512_store_si512(b, best);
    int64_t nearest = INT_MAX, next = INT_MAX, at = -1;
    for (int l = 0; l < 8; ++l) {
      if (f[l] < nearest || (f[l] == nearest && b[l] < at)) {
        next = std::min(next, nearest);
        nearest = f[l], at = b[l];
      } else {
        next = std::min(next, f[l]);
      }
      next = std::min(next, s[l]);
    }
    n.row_best[i] = static_cast<int>(at), n.row_first[i] = static_cast<int>(nearest);
    n.row_second[i] = static_cast<int>(next);
  }
  for (int j = 0; j < cols; ++j) n.col_first[j] = static_cast<int>(col_first[j]), n.col_best[j] = static_cast<int>(col_best[j]);
}

bool haveAvx512Popcount() {
  static const bool have = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vpopcntdq");
  return have;
}
#endif

}  // namespace

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
  Nearest n(a.rows, b.rows);
#ifdef RMAP_HAVE_AVX512_POPCNT_KERNEL
  if (haveAvx512Popcount()) {
    nearestAvx512(pa, pb, blocks, n);
  } else {
    nearestScalar(pa, pb, blocks, n);
  }
#else
  nearestScalar(pa, pb, blocks, n);
#endif
  for (int i = 0; i < a.rows; ++i) {
    const int j = n.row_best[i];
    if (j < 0 || n.row_first[i] > max_bits || n.col_best[j] != i) continue;
    if (n.row_second[i] != INT_MAX && n.row_first[i] >= ratio * n.row_second[i]) continue;
    out.emplace_back(i, j);
  }
  return out;
}

}  // namespace rmap::loop
