#include "sim/loop_course.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace rmap::sim {
namespace {

using Box = Eigen::AlignedBox3d;

/// One straight wall face along the corridor: points p0 + t·along (t ∈ [0, length]),
/// `inward` the unit normal into the corridor, `depth` the wall's own thickness behind the face.
struct WallFace {
  Eigen::Vector2d p0, along, inward;
  double length;
};

class CourseBuilder {
 public:
  CourseBuilder(const LoopCourseOptions& o, uint64_t seed)
      : o_(o),
        rng_(seed),
        world_(VoxelWorld::covering(box(-o.wall_m, -o.wall_m, -o.wall_m, o.size_x_m + o.wall_m,
                                        o.size_y_m + o.wall_m, o.height_m + o.wall_m),
                                    o.voxel_m)) {}

  LoopCourse build() {
    const double sx = o_.size_x_m, sy = o_.size_y_m, c = o_.corridor_width_m, t = o_.wall_m, h = o_.height_m;
    // Floor tiles, ceiling, outer walls, the central block's walls.
    const double tile = 0.5;
    for (double x = -t; x < sx + t; x += tile) {
      for (double y = -t; y < sy + t; y += tile) {
        world_.fillBox(box(x, y, -t, std::min(x + tile, sx + t), std::min(y + tile, sy + t), 0.0), uniform(0.10, 0.45));
      }
    }
    world_.fillBox(box(-t, -t, h, sx + t, sy + t, h + t), uniform(0.6, 0.8));
    const double outer = uniform(0.4, 0.6), inner = uniform(0.4, 0.6);
    world_.fillBox(box(-t, -t, 0, sx + t, 0, h), outer);
    world_.fillBox(box(-t, sy, 0, sx + t, sy + t, h), outer);
    world_.fillBox(box(-t, 0, 0, 0, sy, h), outer);
    world_.fillBox(box(sx, 0, 0, sx + t, sy, h), outer);
    world_.fillBox(box(c, c, 0, sx - c, c + t, h), inner);
    world_.fillBox(box(c, sy - c - t, 0, sx - c, sy - c, h), inner);
    world_.fillBox(box(c, c, 0, c + t, sy - c, h), inner);
    world_.fillBox(box(sx - c - t, c, 0, sx - c, sy - c, h), inner);
    world_.fillBox(box(c, c, h - t, sx - c, sy - c, h), inner);  // lid of the block (seen only from inside it)

    const std::vector<WallFace> faces = {
        {{0, 0}, {1, 0}, {0, 1}, sx},          {{sx, sy}, {-1, 0}, {0, -1}, sx},
        {{0, sy}, {0, -1}, {1, 0}, sy},        {{sx, 0}, {0, 1}, {-1, 0}, sy},
        {{c, c}, {1, 0}, {0, -1}, sx - 2 * c}, {{sx - c, sy - c}, {-1, 0}, {0, 1}, sx - 2 * c},
        {{c, sy - c}, {0, -1}, {-1, 0}, sy - 2 * c}, {{sx - c, c}, {0, 1}, {1, 0}, sy - 2 * c}};
    for (const WallFace& face : faces) posters(face);
    for (const WallFace& face : faces) cabinets(face);
    addVoxelNoise();
    return {std::move(world_), {{0.5 * c, 0.5 * c}, {sx - 0.5 * c, 0.5 * c}, {sx - 0.5 * c, sy - 0.5 * c},
                                {0.5 * c, sy - 0.5 * c}}};
  }

 private:
  double uniform(double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng_); }

  /// The box spanning [t0, t1] along a face, [d0, d1] into the corridor (negative: into the wall), [z0, z1].
  Box faceBox(const WallFace& f, double t0, double t1, double d0, double d1, double z0, double z1) const {
    const Eigen::Vector2d a = f.p0 + t0 * f.along + d0 * f.inward, b = f.p0 + t1 * f.along + d1 * f.inward;
    return box(std::min(a.x(), b.x()), std::min(a.y(), b.y()), z0, std::max(a.x(), b.x()), std::max(a.y(), b.y()), z1);
  }

  void posters(const WallFace& f) {
    const int n = static_cast<int>(std::lround(o_.posters_per_m * f.length));
    for (int i = 0; i < n; ++i) {
      const double w = uniform(0.2, 1.4), hgt = uniform(0.2, 1.4);
      const double t0 = uniform(0.0, std::max(0.0, f.length - w)), z0 = uniform(0.0, o_.height_m - hgt);
      world_.fillBox(faceBox(f, t0, t0 + w, -o_.voxel_m, 0.0, z0, z0 + hgt), uniform(0.05, 0.95));
    }
  }

  void cabinets(const WallFace& f) {
    // Keep the corner squares free: the corridor turns there.
    const double margin = o_.corridor_width_m;
    if (f.length <= 2 * margin + 0.4) return;
    const int n = static_cast<int>(std::lround(o_.cabinets_per_m * f.length));
    const double depth_max = std::min(0.6, 0.5 * o_.corridor_width_m - 0.8);
    for (int i = 0; i < n; ++i) {
      const double len = uniform(0.4, 1.2), depth = uniform(0.3, depth_max), hgt = uniform(0.5, 2.0);
      const double t0 = uniform(margin, f.length - margin - len);
      world_.fillBox(faceBox(f, t0, t0 + len, 0.0, depth, 0.0, hgt), uniform(0.05, 0.9));
    }
  }

  /// Per-voxel variation of every occupied voxel (surfaces and all: the walls are thin).
  void addVoxelNoise() {
    if (o_.voxel_noise <= 0.0) return;
    std::vector<Eigen::Vector3i> voxels;
    world_.forEachOccupiedVoxel([&](const Eigen::Vector3i& v) { voxels.push_back(v); });
    for (const Eigen::Vector3i& v : voxels) {
      const double rho = world_.reflectivityVoxel(v) + uniform(-o_.voxel_noise, o_.voxel_noise);
      world_.fillVoxels(VoxelBox(v, v), static_cast<float>(std::clamp(rho, 0.0, 1.0)));
    }
  }

  const LoopCourseOptions& o_;
  std::mt19937_64 rng_;
  VoxelWorld world_;
};

}  // namespace

void LoopCourseOptions::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("LoopCourseOptions: " + what); };
  if (!(voxel_m > 0.0 && voxel_m <= 0.2)) fail("voxel_m must be in (0, 0.2]");
  if (!(corridor_width_m >= 2.8) || !std::isfinite(corridor_width_m)) fail("corridor_width_m must be ≥ 2.8");
  if (!(size_x_m >= 2 * corridor_width_m + 2) || !(size_y_m >= 2 * corridor_width_m + 2) || !std::isfinite(size_x_m) ||
      !std::isfinite(size_y_m) || size_x_m > 500 || size_y_m > 500) {
    fail("size_x_m and size_y_m must be in [2·corridor_width_m + 2, 500]");
  }
  if (!(height_m >= 2.0 && height_m <= 10.0)) fail("height_m must be in [2, 10]");
  if (!(wall_m >= voxel_m && wall_m <= 1.0)) fail("wall_m must be in [voxel_m, 1]");
  if (!(posters_per_m >= 0.0 && posters_per_m <= 100.0)) fail("posters_per_m must be in [0, 100]");
  if (!(cabinets_per_m >= 0.0 && cabinets_per_m <= 10.0)) fail("cabinets_per_m must be in [0, 10]");
  if (!(voxel_noise >= 0.0 && voxel_noise <= 0.5)) fail("voxel_noise must be in [0, 0.5]");
}

LoopCourse makeLoopCourse(const LoopCourseOptions& options, uint64_t seed) {
  options.validate();
  return CourseBuilder(options, seed).build();
}

}  // namespace rmap::sim
