#include "map3d/fusion.h"

#include <algorithm>

namespace rmap::map3d {
namespace {

/// Running value span of a growing cuboid.
struct Span {
  float lo, hi;
  bool accepts(float v, float tolerance) const { return std::max(hi, v) - std::min(lo, v) <= tolerance; }
  void add(float v) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
};

class BlockFuser {
 public:
  BlockFuser(const DenseCells& cells, float tolerance, float threshold)
      : cells_(cells), tolerance_(tolerance), threshold_(threshold) {}

  std::vector<PackedCuboid> run() {
    std::vector<PackedCuboid> out;
    for (int w = 0; w < kBlockWords; ++w) {
      // re-read the word each round: growing a cuboid takes later cells too
      while (uint64_t open = cells_.known.words[w] & ~taken_.words[w]) {
        out.push_back(grow((w << 6) | std::countr_zero(open)));
      }
    }
    return out;
  }

 private:
  bool usable(int i, bool occupied, const Span& span) const {
    return cells_.known.test(i) && !taken_.test(i) && (cells_.log_odds[i] >= threshold_) == occupied &&
           span.accepts(cells_.log_odds[i], tolerance_);
  }

  /// Tries to add the cells [x0,x1]×[y0,y1]×[z0,z1]; all or nothing.
  bool tryAdd(int x0, int x1, int y0, int y1, int z0, int z1, bool occupied, Span& span) const {
    Span grown = span;
    for (int z = z0; z <= z1; ++z) {
      for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
          const int i = localIndex(x, y, z);
          if (!usable(i, occupied, grown)) return false;
          grown.add(cells_.log_odds[i]);
        }
      }
    }
    span = grown;
    return true;
  }

  PackedCuboid grow(int start) {
    const CellKey s = cellOf(BlockKey{}, start);
    const float v = cells_.log_odds[start];
    const bool occupied = v >= threshold_;
    Span span{v, v};
    int x1 = s.x, y1 = s.y, z1 = s.z;
    while (x1 + 1 < kBlockEdge && tryAdd(x1 + 1, x1 + 1, s.y, s.y, s.z, s.z, occupied, span)) ++x1;
    while (y1 + 1 < kBlockEdge && tryAdd(s.x, x1, y1 + 1, y1 + 1, s.z, s.z, occupied, span)) ++y1;
    while (z1 + 1 < kBlockEdge && tryAdd(s.x, x1, s.y, y1, z1 + 1, z1 + 1, occupied, span)) ++z1;
    for (int z = s.z; z <= z1; ++z) {
      for (int y = s.y; y <= y1; ++y) {
        for (int x = s.x; x <= x1; ++x) taken_.set(localIndex(x, y, z));
      }
    }
    PackedCuboid c;
    c.lo_packed = PackedCuboid::pack(s.x, s.y, s.z);
    c.hi_packed = PackedCuboid::pack(x1, y1, z1);
    // the middle keeps every cell within tolerance/2 and on its side of the threshold
    c.log_odds = span.lo == span.hi ? span.lo : 0.5f * (span.lo + span.hi);
    if ((c.log_odds >= threshold_) != occupied) c.log_odds = occupied ? span.lo : span.hi;  // float rounding at the threshold
    return c;
  }

  const DenseCells& cells_;
  float tolerance_;
  float threshold_;
  BlockBits taken_;
};

}  // namespace

std::vector<PackedCuboid> fuseBlock(const DenseCells& cells, float tolerance, float occupied_threshold) {
  return BlockFuser(cells, tolerance, occupied_threshold).run();
}

void expandCuboids(const std::vector<PackedCuboid>& cuboids, DenseCells& cells) {
  for (const PackedCuboid& c : cuboids) {
    for (int z = c.lo(2); z <= c.hi(2); ++z) {
      for (int y = c.lo(1); y <= c.hi(1); ++y) {
        for (int x = c.lo(0); x <= c.hi(0); ++x) {
          const int i = localIndex(x, y, z);
          cells.log_odds[i] = c.log_odds;
          cells.known.set(i);
        }
      }
    }
  }
}

int findCuboid(const std::vector<PackedCuboid>& cuboids, int x, int y, int z) {
  for (size_t i = 0; i < cuboids.size(); ++i) {
    if (cuboids[i].contains(x, y, z)) return static_cast<int>(i);
  }
  return -1;
}

SliceIndex::SliceIndex(const std::vector<PackedCuboid>& fused) {
  for (const PackedCuboid& c : fused) {
    for (int z = c.lo(2); z <= c.hi(2); ++z) ++offsets[z + 1];
  }
  for (int z = 0; z < kBlockEdge; ++z) offsets[z + 1] += offsets[z];
  cuboids.resize(offsets[kBlockEdge]);
  std::array<uint32_t, kBlockEdge> fill{};
  for (size_t i = 0; i < fused.size(); ++i) {
    for (int z = fused[i].lo(2); z <= fused[i].hi(2); ++z) {
      cuboids[offsets[z] + fill[z]++] = static_cast<uint16_t>(i);
    }
  }
}

int SliceIndex::find(const std::vector<PackedCuboid>& fused, int x, int y, int z) const {
  for (uint32_t k = offsets[z]; k < offsets[z + 1]; ++k) {
    if (fused[cuboids[k]].contains(x, y, z)) return cuboids[k];
  }
  return -1;
}

}  // namespace rmap::map3d
