#include "map3d/cuboid_map.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#include "map3d/fusion.h"
#include "map3d/parallel_for.h"
#include "map3d/ray_traversal.h"

namespace rmap::map3d {

const char* toString(CellState state) {
  switch (state) {
    case CellState::kFree:
      return "free";
    case CellState::kOccupied:
      return "occupied";
    default:
      return "unknown";
  }
}

struct CuboidMap::Block {
  BlockKey key;
  std::unique_ptr<DenseCells> dense;  ///< hot form; null when fused
  std::vector<PackedCuboid> cuboids;  ///< fused form; empty while hot
  std::unique_ptr<SliceIndex> slices;  ///< lookup index of a fused block with many cuboids
  uint64_t last_update_scan = 0;
  uint64_t version = 0;
  int32_t hot_index = -1;  ///< position in hot_, -1 when fused
};

namespace {

CuboidBox toWorld(const BlockKey& b, const PackedCuboid& c) {
  CuboidBox box;
  box.min = {(b.x << kBlockShift) + c.lo(0), (b.y << kBlockShift) + c.lo(1), (b.z << kBlockShift) + c.lo(2)};
  box.max = {(b.x << kBlockShift) + c.hi(0), (b.y << kBlockShift) + c.hi(1), (b.z << kBlockShift) + c.hi(2)};
  box.log_odds = c.log_odds;
  return box;
}

bool intersects(const CuboidBox& box, const CellKey& min, const CellKey& max) {
  for (int a = 0; a < 3; ++a) {
    if (box.max[a] < min[a] || box.min[a] > max[a]) return false;
  }
  return true;
}

void validateParams(double resolution_m, const OccupancyParams& o, const FusionParams& f) {
  if (!std::isfinite(resolution_m) || resolution_m <= 0.0) {
    throw std::invalid_argument("resolution must be finite and > 0 m, got " + std::to_string(resolution_m));
  }
  if (!(o.hit_log_odds > 0.0f) || !(o.miss_log_odds < 0.0f)) {
    throw std::invalid_argument("hit log-odds must be > 0 and miss log-odds < 0");
  }
  if (!(o.clamp_min_log_odds < o.occupied_threshold_log_odds && o.occupied_threshold_log_odds < o.clamp_max_log_odds)) {
    throw std::invalid_argument("clamps must satisfy clamp_min < occupied_threshold < clamp_max");
  }
  if (!(f.tolerance_log_odds >= 0.0f) || !std::isfinite(f.tolerance_log_odds)) {
    throw std::invalid_argument("fusion tolerance must be finite and >= 0");
  }
  if (f.fuse_after_scans < 0) throw std::invalid_argument("fuse_after_scans must be >= 0");
  if (o.stop_after_freed_cells < 2) throw std::invalid_argument("stop_after_freed_cells must be >= 2");
  if (std::isnan(o.max_range_m)) throw std::invalid_argument("max_range_m must not be NaN (< 0 means unlimited)");
}

}  // namespace

CuboidMap::CuboidMap(double resolution_m, const OccupancyParams& occupancy, const FusionParams& fusion)
    : grid_(resolution_m > 0.0 ? resolution_m : 1.0), occupancy_(occupancy), fusion_(fusion) {
  validateParams(resolution_m, occupancy, fusion);
}

CuboidMap::~CuboidMap() = default;

// ---------------------------------------------------------------- writing

ScanStats CuboidMap::insertScan(const Eigen::Vector3f& sensor_origin_m, std::span<const Eigen::Vector3f> points_m,
                                const InsertOptions& options) {
  if (points_m.empty()) throw std::invalid_argument("empty scan: no points to integrate");
  if (options.threads < 1) throw std::invalid_argument("threads must be >= 1");
  CellKey origin_cell;
  if (!grid_.cellChecked(sensor_origin_m, origin_cell)) {
    throw std::invalid_argument("sensor origin is not finite or outside the map's addressable range");
  }
  if (options.invalid_points == InvalidPoints::kReject) {
    CellKey c;
    for (size_t i = 0; i < points_m.size(); ++i) {
      if (!grid_.cellChecked(points_m[i], c)) {
        throw std::invalid_argument("point " + std::to_string(i) + " of the scan is " +
                                    (points_m[i].allFinite() ? "outside the map's addressable range"
                                                             : "not finite (NaN/inf)") +
                                    "; scan rejected");
      }
    }
  }

  // Trace rays without the lock: readers keep querying meanwhile.
  ScanUpdate update;
  const size_t threads = std::min<size_t>(options.threads, std::max<size_t>(1, points_m.size() / 1024));
  if (threads <= 1) {
    update.gather(grid_, occupancy_, sensor_origin_m, points_m);
  } else {
    std::vector<ScanUpdate> parts(threads);
    std::vector<std::thread> workers;
    const size_t chunk = (points_m.size() + threads - 1) / threads;
    for (size_t t = 0; t < threads; ++t) {
      const size_t begin = std::min(points_m.size(), t * chunk);
      const size_t end = std::min(points_m.size(), begin + chunk);
      workers.emplace_back([&, t, begin, end] {
        parts[t].gather(grid_, occupancy_, sensor_origin_m, points_m.subspan(begin, end - begin));
      });
    }
    for (std::thread& w : workers) w.join();
    for (ScanUpdate& part : parts) update.merge(std::move(part));
  }
  update.resolve();

  std::unique_lock lock(mutex_);
  ++scans_;
  ++version_;
  applyUpdate(update, options.threads);
  fuseColdBlocks(options.threads);
  return update.stats();
}

CuboidMap::Block& CuboidMap::findOrCreate(const BlockKey& key) {
  auto [it, inserted] = blocks_.try_emplace(key);
  if (inserted) {
    it->second = std::make_unique<Block>();
    it->second->key = key;
  }
  return *it->second;
}

CuboidMap::Block& CuboidMap::blockForWrite(const BlockKey& key) {
  Block& block = findOrCreate(key);
  if (!block.dense) {
    makeHot(block);
    fillFromCuboids(block);
  }
  return block;
}

void CuboidMap::makeHot(Block& block) {
  block.dense.reset(new DenseCells);  // default-init: only the known bits are zeroed, values are written before use
  block.hot_index = static_cast<int32_t>(hot_.size());
  hot_.push_back(&block);
}

void CuboidMap::fillFromCuboids(Block& block) {
  expandCuboids(block.cuboids, *block.dense);
  block.cuboids.clear();
  block.cuboids.shrink_to_fit();
  block.slices.reset();
}

void CuboidMap::fuseBlocks(const std::vector<Block*>& blocks, int threads) {
  parallelFor(blocks.size(), threads, [&](size_t i) {
    Block& block = *blocks[i];
    block.cuboids = fuseBlock(*block.dense, fusion_.tolerance_log_odds, occupancy_.occupied_threshold_log_odds);
    block.cuboids.shrink_to_fit();
    if (block.cuboids.size() >= SliceIndex::kMinCuboids) block.slices = std::make_unique<SliceIndex>(block.cuboids);
    block.dense.reset();
  });
  for (Block* block : blocks) {
    // swap-remove from the hot list
    Block* last = hot_.back();
    hot_[block->hot_index] = last;
    last->hot_index = block->hot_index;
    hot_.pop_back();
    block->hot_index = -1;
  }
}

void CuboidMap::applyUpdate(const ScanUpdate& update, int threads) {
  struct Job {
    Block* block;
    const BlockMarks* marks;
    bool fill;  ///< the block was fused: expand its cuboids first
  };
  std::vector<Job> jobs;
  jobs.reserve(update.blocks().size());
  for (const BlockMarks& marks : update.blocks()) {
    if (!marks.free.any() && !marks.occupied.any()) continue;
    Block& block = findOrCreate(marks.key);
    const bool fill = !block.dense;
    if (fill) makeHot(block);
    jobs.push_back({&block, &marks, fill});
  }
  const float hit = occupancy_.hit_log_odds;
  const float miss = occupancy_.miss_log_odds;
  const float lo = occupancy_.clamp_min_log_odds;
  const float hi = occupancy_.clamp_max_log_odds;
  parallelFor(jobs.size(), threads, [&](size_t j) {
    const Job& job = jobs[j];
    Block& block = *job.block;
    if (job.fill) fillFromCuboids(block);
    DenseCells& cells = *block.dense;
    // Word by word, so the known bits are read and written once per 64 cells.
    // Same float arithmetic as OctoMap: new cells start at 0, add, then clamp.
    for (int w = 0; w < kBlockWords; ++w) {
      const uint64_t freed = job.marks->free.words[w], hit_bits = job.marks->occupied.words[w];
      if (!(freed | hit_bits)) continue;
      const uint64_t known = cells.known.words[w];
      float* values = &cells.log_odds[w << 6];
      auto apply = [&](uint64_t bits, float delta) {
        for (; bits; bits &= bits - 1) {
          const int b = std::countr_zero(bits);
          const float v = (known >> b) & 1 ? values[b] : 0.0f;
          values[b] = std::clamp(v + delta, lo, hi);
        }
      };
      apply(freed, miss);
      apply(hit_bits, hit);
      cells.known.words[w] = known | freed | hit_bits;
    }
    block.last_update_scan = scans_;
    block.version = version_;
  });
}

void CuboidMap::fuseColdBlocks(int threads) {
  std::vector<Block*> cold;
  for (Block* block : hot_) {
    if (scans_ - block->last_update_scan >= static_cast<uint64_t>(fusion_.fuse_after_scans)) cold.push_back(block);
  }
  fuseBlocks(cold, threads);
}

void CuboidMap::fuseAll(int threads) {
  std::unique_lock lock(mutex_);
  fuseBlocks(std::vector<Block*>(hot_), threads);
}

void CuboidMap::replaceBlocks(std::vector<std::pair<BlockKey, std::vector<PackedCuboid>>> blocks) {
  for (const auto& [key, cuboids] : blocks) {
    BlockBits seen;
    for (const PackedCuboid& c : cuboids) {
      bool ok = std::isfinite(c.log_odds) && c.log_odds >= occupancy_.clamp_min_log_odds &&
                c.log_odds <= occupancy_.clamp_max_log_odds && (c.lo_packed >> 12) == 0 && (c.hi_packed >> 12) == 0;
      for (int a = 0; ok && a < 3; ++a) ok = c.lo(a) <= c.hi(a);
      for (int z = c.lo(2); ok && z <= c.hi(2); ++z) {
        for (int y = c.lo(1); ok && y <= c.hi(1); ++y) {
          for (int x = c.lo(0); ok && x <= c.hi(0); ++x) {
            const int i = localIndex(x, y, z);
            ok = !seen.test(i);
            seen.set(i);
          }
        }
      }
      constexpr int32_t kBlockLimit = kCellLimit / kBlockEdge;
      for (int32_t k : {key.x, key.y, key.z}) ok = ok && k >= -kBlockLimit && k < kBlockLimit;
      if (!ok) {
        throw std::invalid_argument("block (" + std::to_string(key.x) + "," + std::to_string(key.y) + "," +
                                    std::to_string(key.z) +
                                    ") has a cuboid out of the block, overlapping another, or with an invalid value");
      }
    }
  }
  std::unique_lock lock(mutex_);
  ++version_;
  for (auto& [key, cuboids] : blocks) {
    Block& block = blockForWrite(key);
    block.dense->known = BlockBits{};
    expandCuboids(cuboids, *block.dense);
    block.version = version_;
  }
  fuseBlocks(std::vector<Block*>(hot_), 1);
}

void CuboidMap::setCuboids(std::span<const CuboidBox> boxes) {
  for (const CuboidBox& b : boxes) {
    if (!cellInRange(b.min) || !cellInRange(b.max) || b.min.x > b.max.x || b.min.y > b.max.y || b.min.z > b.max.z ||
        !std::isfinite(b.log_odds)) {
      throw std::invalid_argument("cuboid outside the addressable range, inverted or with a non-finite value");
    }
  }
  std::unique_lock lock(mutex_);
  ++version_;
  const float lo = occupancy_.clamp_min_log_odds, hi = occupancy_.clamp_max_log_odds;
  for (const CuboidBox& b : boxes) {
    const BlockKey bmin = blockOf(b.min), bmax = blockOf(b.max);
    for (int32_t bz = bmin.z; bz <= bmax.z; ++bz) {
      for (int32_t by = bmin.y; by <= bmax.y; ++by) {
        for (int32_t bx = bmin.x; bx <= bmax.x; ++bx) {
          Block& block = blockForWrite({bx, by, bz});
          const CellKey base{bx << kBlockShift, by << kBlockShift, bz << kBlockShift};
          int lo_c[3], hi_c[3];
          for (int a = 0; a < 3; ++a) {
            lo_c[a] = std::max(b.min[a], base[a]) - base[a];
            hi_c[a] = std::min(b.max[a], base[a] + kBlockEdge - 1) - base[a];
          }
          for (int z = lo_c[2]; z <= hi_c[2]; ++z) {
            for (int y = lo_c[1]; y <= hi_c[1]; ++y) {
              for (int x = lo_c[0]; x <= hi_c[0]; ++x) {
                const int i = localIndex(x, y, z);
                block.dense->log_odds[i] = std::clamp(b.log_odds, lo, hi);
                block.dense->known.set(i);
              }
            }
          }
          block.version = version_;
        }
      }
    }
  }
  fuseBlocks(std::vector<Block*>(hot_), 1);
}

void CuboidMap::rewriteCells(const CellKey& min, const CellKey& max,
                             const std::function<std::optional<float>(const CellKey&)>& value) {
  if (!cellInRange(min) || !cellInRange(max) || min.x > max.x || min.y > max.y || min.z > max.z) {
    throw std::invalid_argument("rewriteCells: range outside the addressable cells or inverted");
  }
  // Values first, block by block, so a bad one leaves the map unchanged and the lock is short.
  struct BlockValues {
    BlockKey key;
    std::vector<std::pair<int, std::optional<float>>> cells;  ///< local index, value
    bool any_known = false;
  };
  std::vector<BlockValues> blocks;
  const BlockKey bmin = blockOf(min), bmax = blockOf(max);
  for (int32_t bz = bmin.z; bz <= bmax.z; ++bz) {
    for (int32_t by = bmin.y; by <= bmax.y; ++by) {
      for (int32_t bx = bmin.x; bx <= bmax.x; ++bx) {
        BlockValues& b = blocks.emplace_back();
        b.key = {bx, by, bz};
        const CellKey base{bx << kBlockShift, by << kBlockShift, bz << kBlockShift};
        for (int32_t z = std::max(min.z, base.z); z <= std::min(max.z, base.z + kBlockEdge - 1); ++z) {
          for (int32_t y = std::max(min.y, base.y); y <= std::min(max.y, base.y + kBlockEdge - 1); ++y) {
            for (int32_t x = std::max(min.x, base.x); x <= std::min(max.x, base.x + kBlockEdge - 1); ++x) {
              const CellKey cell{x, y, z};
              const std::optional<float> v = value(cell);
              if (v && !std::isfinite(*v)) throw std::invalid_argument("rewriteCells: non-finite log-odds");
              b.any_known = b.any_known || v.has_value();
              b.cells.emplace_back(localIndex(cell), v);
            }
          }
        }
      }
    }
  }
  std::unique_lock lock(mutex_);
  ++version_;
  const float lo = occupancy_.clamp_min_log_odds, hi = occupancy_.clamp_max_log_odds;
  std::vector<Block*> touched;
  for (const BlockValues& b : blocks) {
    if (!b.any_known && !blocks_.contains(b.key)) continue;
    Block& block = blockForWrite(b.key);
    for (const auto& [i, v] : b.cells) {
      if (v) {
        block.dense->log_odds[i] = std::clamp(*v, lo, hi);
        block.dense->known.set(i);
      } else {
        block.dense->known.reset(i);
      }
    }
    block.version = version_;
    touched.push_back(&block);
  }
  fuseBlocks(touched, 1);
}

// ---------------------------------------------------------------- reading

CellQuery CuboidMap::query(const Eigen::Vector3d& point_m) const {
  // Not rounded to float: that can move a point across a cell edge.
  CellKey cell;
  if (!grid_.cellChecked(point_m, cell)) return {};
  return queryCell(cell);
}

CellQuery CuboidMap::queryCell(const CellKey& cell) const {
  std::shared_lock lock(mutex_);
  return queryCellLocked(cell);
}

CellQuery CuboidMap::queryCellLocked(const CellKey& cell) const {
  CellQuery q;
  const auto it = blocks_.find(blockOf(cell));
  if (it == blocks_.end()) return q;
  const Block& block = *it->second;
  const int i = localIndex(cell);
  if (block.dense) {
    if (!block.dense->known.test(i)) return q;
    q.log_odds = block.dense->log_odds[i];
    q.cuboid = {cell, cell, q.log_odds};
  } else {
    constexpr int m = kBlockEdge - 1;
    const int x = cell.x & m, y = cell.y & m, z = cell.z & m;
    const int found = block.slices ? block.slices->find(block.cuboids, x, y, z) : findCuboid(block.cuboids, x, y, z);
    if (found < 0) return q;
    q.cuboid = toWorld(block.key, block.cuboids[found]);
    q.log_odds = q.cuboid.log_odds;
  }
  q.state = q.log_odds >= occupancy_.occupied_threshold_log_odds ? CellState::kOccupied : CellState::kFree;
  q.probability = probability(q.log_odds);
  return q;
}

void CuboidMap::forEachCuboid(const CellKey& min, const CellKey& max,
                              const std::function<bool(const CuboidBox&)>& fn) const {
  std::shared_lock lock(mutex_);
  const BlockKey bmin = blockOf(min), bmax = blockOf(max);
  auto visitBlock = [&](const Block& block) {
    std::vector<PackedCuboid> on_the_fly;
    const std::vector<PackedCuboid>* cuboids = &block.cuboids;
    if (block.dense) {
      on_the_fly = fuseBlock(*block.dense, fusion_.tolerance_log_odds, occupancy_.occupied_threshold_log_odds);
      cuboids = &on_the_fly;
    }
    for (const PackedCuboid& c : *cuboids) {
      const CuboidBox box = toWorld(block.key, c);
      if (intersects(box, min, max) && !fn(box)) return false;
    }
    return true;
  };
  const double span = (double(bmax.x) - bmin.x + 1) * (double(bmax.y) - bmin.y + 1) * (double(bmax.z) - bmin.z + 1);
  if (span <= 0) return;
  if (span < static_cast<double>(blocks_.size())) {
    for (int32_t z = bmin.z; z <= bmax.z; ++z) {
      for (int32_t y = bmin.y; y <= bmax.y; ++y) {
        for (int32_t x = bmin.x; x <= bmax.x; ++x) {
          const auto it = blocks_.find({x, y, z});
          if (it != blocks_.end() && !visitBlock(*it->second)) return;
        }
      }
    }
  } else {
    for (const auto& [key, block] : blocks_) {
      if (key.x < bmin.x || key.x > bmax.x || key.y < bmin.y || key.y > bmax.y || key.z < bmin.z || key.z > bmax.z) {
        continue;
      }
      if (!visitBlock(*block)) return;
    }
  }
}

std::vector<CuboidBox> CuboidMap::queryBox(const Eigen::AlignedBox3d& box_m, size_t limit) const {
  std::vector<CuboidBox> out;
  if (box_m.isEmpty() || !box_m.min().allFinite() || !box_m.max().allFinite()) return out;
  CellKey min, max;
  for (int a = 0; a < 3; ++a) {
    min[a] = grid_.index(box_m.min()[a]);
    max[a] = grid_.index(box_m.max()[a]);
  }
  forEachCuboid(min, max, [&](const CuboidBox& c) {
    if (out.size() >= limit) return false;
    out.push_back(c);
    return true;
  });
  return out;
}

std::vector<CuboidBox> CuboidMap::levelOfDetail(int level, const CellKey& min, const CellKey& max) const {
  if (level < 0 || level > 16) throw std::invalid_argument("level of detail must be in [0, 16]");
  std::vector<CuboidBox> out;
  if (level == 0) {
    forEachCuboid(min, max, [&](const CuboidBox& c) {
      out.push_back(c);
      return true;
    });
    return out;
  }
  // Max-pool known cells into coarse cells, grouped in coarse blocks of 16³.
  std::unordered_map<BlockKey, DenseCells, BlockKeyHash> coarse;
  forEachCuboid(min, max, [&](const CuboidBox& c) {
    CellKey cmin, cmax;
    for (int a = 0; a < 3; ++a) {
      cmin[a] = std::max(c.min[a], min[a]) >> level;
      cmax[a] = std::min(c.max[a], max[a]) >> level;
    }
    for (int32_t z = cmin.z; z <= cmax.z; ++z) {
      for (int32_t y = cmin.y; y <= cmax.y; ++y) {
        for (int32_t x = cmin.x; x <= cmax.x; ++x) {
          const CellKey cc{x, y, z};
          auto [it, inserted] = coarse.try_emplace(blockOf(cc));
          DenseCells& cells = it->second;
          const int i = localIndex(cc);
          cells.log_odds[i] = cells.known.test(i) ? std::max(cells.log_odds[i], c.log_odds) : c.log_odds;
          cells.known.set(i);
        }
      }
    }
    return true;
  });
  for (const auto& [key, cells] : coarse) {
    for (const PackedCuboid& c : fuseBlock(cells, fusion_.tolerance_log_odds, occupancy_.occupied_threshold_log_odds)) {
      CuboidBox box = toWorld(key, c);
      for (int a = 0; a < 3; ++a) {
        box.min[a] = box.min[a] << level;
        box.max[a] = ((box.max[a] + 1) << level) - 1;
      }
      out.push_back(box);
    }
  }
  return out;
}

RayCastResult CuboidMap::castRay(const Eigen::Vector3d& origin_m, const Eigen::Vector3d& direction,
                                 double max_range_m, bool ignore_unknown) const {
  RayCastResult result;
  const double norm = direction.norm();
  if (!origin_m.allFinite() || !direction.allFinite() || !(norm > 0.0) || !(max_range_m > 0.0) ||
      !std::isfinite(max_range_m)) {
    return result;
  }
  const Eigen::Vector3d end = origin_m + direction / norm * max_range_m;
  RayWalker walker;
  if (!walker.init(grid_, origin_m.cast<float>(), end.cast<float>())) return result;
  std::shared_lock lock(mutex_);
  double entry_m = 0.0;
  while (true) {
    const CellQuery q = queryCellLocked(walker.cell());
    if (q.state == CellState::kOccupied || (q.state == CellState::kUnknown && !ignore_unknown)) {
      result.outcome =
          q.state == CellState::kOccupied ? RayCastResult::Outcome::kHitOccupied : RayCastResult::Outcome::kHitUnknown;
      result.cell = walker.cell();
      result.distance_m = entry_m;
      return result;
    }
    if (walker.atEnd() || walker.exitDistance() > walker.length()) break;
    entry_m = walker.exitDistance();
    walker.step();
  }
  result.outcome = RayCastResult::Outcome::kMaxRange;
  result.cell = walker.cell();
  result.distance_m = max_range_m;
  return result;
}

void CuboidMap::forEachKnownCell(const std::function<void(const CellKey&, float)>& fn) const {
  std::shared_lock lock(mutex_);
  for (const auto& [key, block] : blocks_) {
    if (block->dense) {
      // Named captures: clang before 16 cannot capture structured bindings implicitly.
      block->dense->known.forEach([&fn, &key = key, &block = block](int i) { fn(cellOf(key, i), block->dense->log_odds[i]); });
      continue;
    }
    for (const PackedCuboid& c : block->cuboids) {
      const CuboidBox box = toWorld(key, c);
      for (int32_t z = box.min.z; z <= box.max.z; ++z) {
        for (int32_t y = box.min.y; y <= box.max.y; ++y) {
          for (int32_t x = box.min.x; x <= box.max.x; ++x) fn({x, y, z}, c.log_odds);
        }
      }
    }
  }
}

void CuboidMap::forEachBlock(const std::function<void(const BlockView&)>& fn) const {
  std::shared_lock lock(mutex_);
  for (const auto& [key, block] : blocks_) {
    BlockView view{key, block->version, block->cuboids};
    std::vector<PackedCuboid> on_the_fly;
    if (block->dense) {
      on_the_fly = fuseBlock(*block->dense, fusion_.tolerance_log_odds, occupancy_.occupied_threshold_log_odds);
      view.cuboids = on_the_fly;
    }
    fn(view);
  }
}

void CuboidMap::forEachBlockVersion(const std::function<void(const BlockKey&, uint64_t)>& fn) const {
  std::shared_lock lock(mutex_);
  for (const auto& [key, block] : blocks_) fn(key, block->version);
}

bool CuboidMap::bounds(CellKey& min, CellKey& max) const {
  bool any = false;
  forEachBlock([&](const BlockView& view) {
    for (const PackedCuboid& c : view.cuboids) {
      const CuboidBox box = toWorld(view.key, c);
      for (int a = 0; a < 3; ++a) {
        min[a] = any ? std::min(min[a], box.min[a]) : box.min[a];
        max[a] = any ? std::max(max[a], box.max[a]) : box.max[a];
      }
      any = true;
    }
  });
  return any;
}

uint64_t CuboidMap::memoryBytesLocked() const {
  // libstdc++ hash node: next pointer, value, cached hash.
  const uint64_t node_bytes = sizeof(void*) + sizeof(std::pair<const BlockKey, std::unique_ptr<Block>>) + sizeof(size_t);
  uint64_t bytes = sizeof(*this) + blocks_.bucket_count() * sizeof(void*) + blocks_.size() * node_bytes +
                   hot_.capacity() * sizeof(Block*);
  for (const auto& [key, block] : blocks_) {
    bytes += sizeof(Block) + block->cuboids.capacity() * sizeof(PackedCuboid);
    if (block->slices) bytes += block->slices->memoryBytes();
    if (block->dense) bytes += sizeof(DenseCells);
  }
  return bytes;
}

uint64_t CuboidMap::memoryBytes() const {
  std::shared_lock lock(mutex_);
  return memoryBytesLocked();
}

MapStats CuboidMap::stats() const {
  std::shared_lock lock(mutex_);
  MapStats s;
  s.blocks = blocks_.size();
  s.hot_blocks = hot_.size();
  s.scans = scans_;
  s.version = version_;
  s.memory_bytes = memoryBytesLocked();
  for (const auto& [key, block] : blocks_) {
    if (block->dense) {
      const DenseCells& d = *block->dense;
      const int known = d.known.count();
      s.cuboids += known;
      s.known_cells += known;
      d.known.forEach([&](int i) { s.occupied_cells += d.log_odds[i] >= occupancy_.occupied_threshold_log_odds; });
    } else {
      s.cuboids += block->cuboids.size();
      for (const PackedCuboid& c : block->cuboids) {
        s.known_cells += c.cellCount();
        if (c.log_odds >= occupancy_.occupied_threshold_log_odds) s.occupied_cells += c.cellCount();
      }
    }
  }
  return s;
}

uint64_t CuboidMap::version() const {
  std::shared_lock lock(mutex_);
  return version_;
}

}  // namespace rmap::map3d
