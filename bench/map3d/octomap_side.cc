#include "map3d/octomap_side.h"

#include <omp.h>
#include <octomap/OcTree.h>

namespace rmap::bench {
namespace {

constexpr int32_t kTreeMaxVal = 32768;  // OctoMap key of cell index 0

octomap::OcTreeKey toKey(const map3d::CellKey& c) {
  return octomap::OcTreeKey(static_cast<octomap::key_type>(c.x + kTreeMaxVal),
                            static_cast<octomap::key_type>(c.y + kTreeMaxVal),
                            static_cast<octomap::key_type>(c.z + kTreeMaxVal));
}

octomap::point3d toPoint(const Eigen::Vector3f& p) { return {p.x(), p.y(), p.z()}; }

}  // namespace

OctomapSide::OctomapSide(double resolution_m, const map3d::OccupancyParams& params, int threads) : params_(params) {
  // OcTree sizes its per-thread key rays from the OpenMP team at construction.
  omp_set_num_threads(threads);
  tree_ = std::make_unique<octomap::OcTree>(resolution_m);
  const map3d::OccupancyParams defaults;
  if (params.hit_log_odds == defaults.hit_log_odds && params.miss_log_odds == defaults.miss_log_odds &&
      params.clamp_min_log_odds == defaults.clamp_min_log_odds &&
      params.clamp_max_log_odds == defaults.clamp_max_log_odds &&
      params.occupied_threshold_log_odds == defaults.occupied_threshold_log_odds) {
    return;  // OctoMap's own defaults: converting through probabilities could move the last float bit
  }
  tree_->setProbHit(map3d::probability(params.hit_log_odds));
  tree_->setProbMiss(map3d::probability(params.miss_log_odds));
  tree_->setClampingThresMin(map3d::probability(params.clamp_min_log_odds));
  tree_->setClampingThresMax(map3d::probability(params.clamp_max_log_odds));
  tree_->setOccupancyThres(map3d::probability(params.occupied_threshold_log_odds));
}

OctomapSide::~OctomapSide() = default;

void OctomapSide::prepare(const std::vector<datasets::PointScan>& scans) {
  clouds_.assign(scans.size(), {});
  origins_.clear();
  for (size_t i = 0; i < scans.size(); ++i) {
    clouds_[i].reserve(scans[i].points_m.size());
    for (const Eigen::Vector3f& p : scans[i].points_m) clouds_[i].push_back(toPoint(p));
    origins_.push_back(scans[i].sensor_origin_m);
  }
}

void OctomapSide::insert(size_t i) {
  const octomap::Pointcloud& cloud = clouds_.at(i);
  const octomap::point3d origin = toPoint(origins_.at(i));
  if (params_.sensor_model == map3d::SensorModel::kBeam) {
    tree_->insertPointCloud(cloud, origin, params_.max_range_m, false, false);
    return;
  }
  octomap::KeySet endpoints;
  for (size_t j = 0; j < cloud.size(); ++j) {
    const octomap::point3d& q = cloud[j];
    if (params_.max_range_m >= 0.0 && (q - origin).norm() > params_.max_range_m) continue;
    octomap::OcTreeKey key;
    if (tree_->coordToKeyChecked(q, key)) endpoints.insert(key);
  }
  for (const octomap::OcTreeKey& key : endpoints) tree_->updateNode(key, true, false);
}

void OctomapSide::finish() { tree_->prune(); }

map3d::CellState OctomapSide::state(const map3d::CellKey& cell) const {
  if (!map3d::cellInRange(cell)) return map3d::CellState::kUnknown;
  const octomap::OcTreeNode* node = tree_->search(toKey(cell));
  if (!node) return map3d::CellState::kUnknown;
  return tree_->isNodeOccupied(node) ? map3d::CellState::kOccupied : map3d::CellState::kFree;
}

size_t OctomapSide::memoryBytes() const { return tree_->memoryUsage(); }
size_t OctomapSide::leaves() const { return tree_->getNumLeafNodes(); }

void OctomapSide::forEachKnownCell(
    const std::function<void(const map3d::CellKey&, map3d::CellState)>& fn) const {
  for (auto it = tree_->begin_leafs(), end = tree_->end_leafs(); it != end; ++it) {
    const octomap::OcTreeKey k = it.getKey();
    const int size = 1 << (tree_->getTreeDepth() - it.getDepth());
    const map3d::CellState s = tree_->isNodeOccupied(*it) ? map3d::CellState::kOccupied : map3d::CellState::kFree;
    // the leaf key is the key of one cell inside it; align to the cube's corner
    const int32_t x0 = (k[0] & ~(size - 1)) - kTreeMaxVal, y0 = (k[1] & ~(size - 1)) - kTreeMaxVal,
                  z0 = (k[2] & ~(size - 1)) - kTreeMaxVal;
    for (int32_t z = z0; z < z0 + size; ++z) {
      for (int32_t y = y0; y < y0 + size; ++y) {
        for (int32_t x = x0; x < x0 + size; ++x) fn({x, y, z}, s);
      }
    }
  }
}

uint64_t OctomapSide::knownCells() const {
  uint64_t cells = 0;
  for (auto it = tree_->begin_leafs(), end = tree_->end_leafs(); it != end; ++it) {
    const uint64_t size = uint64_t{1} << (tree_->getTreeDepth() - it.getDepth());
    cells += size * size * size;
  }
  return cells;
}

}  // namespace rmap::bench
