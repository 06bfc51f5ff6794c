#include "sim/building.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace rmap::sim {
namespace {

using Box = Eigen::AlignedBox3d;

constexpr double kTread_m = 0.28;     ///< stair step depth
constexpr double kMaxRise_m = 0.19;   ///< steepest step height of a comfortable stair
constexpr double kBoard_m = 0.05;     ///< furniture panel thickness (at least one voxel is used)
constexpr double kTableTop_m = 0.04;  ///< table top thickness (at least one voxel is used)
constexpr double kDoorApproach_m = 1.3;  ///< furniture-free depth in front of a door
constexpr double kFurnitureGap_m = 0.6;  ///< least free gap between furniture pieces

struct StairGeometry {
  int steps;
  double rise, run, landing;
};

StairGeometry stairGeometry(const BuildingOptions& o) {
  const int steps = static_cast<int>(std::ceil(o.floor_height_m / kMaxRise_m - 1e-9));
  return {steps, o.floor_height_m / steps, steps * kTread_m, std::max(1.2, o.stair_width_m)};
}

/// Rooms that fit in one strip along the corridor.
int roomsPerStrip(const BuildingOptions& o, double strip_length) {
  return static_cast<int>(std::floor((strip_length + o.inner_wall_m) / (o.min_room_width_m + o.inner_wall_m)));
}

/// A 2D rectangle in the floor plan.
struct Rect {
  double x0, y0, x1, y1;
  bool overlaps(const Rect& r, double gap = 0.0) const {
    return x0 < r.x1 + gap && r.x0 < x1 + gap && y0 < r.y1 + gap && r.y0 < y1 + gap;
  }
};

class Builder {
 public:
  Builder(const BuildingOptions& o, uint64_t seed, BuildingLayout& layout)
      : o_(o),
        rng_(seed),
        layout_(layout),
        world_(VoxelWorld::covering(box(0, 0, -o.slab_thickness_m, o.size_x_m, o.size_y_m, o.floors * o.floor_height_m),
                                    o.voxel_m)) {}

  VoxelWorld build() {
    const double w = o_.outer_wall_m, t = o_.inner_wall_m;
    xi0_ = w;
    xi1_ = o_.size_x_m - w;
    yi0_ = w;
    yi1_ = o_.size_y_m - w;
    const double depth_slack = 0.5 * (yi1_ - yi0_ - o_.corridor_width_m) - t - o_.min_room_width_m;
    const double jitter = std::min(0.1 * o_.size_y_m, depth_slack);
    const double yc = 0.5 * o_.size_y_m + uniform(-jitter, jitter);
    yc0_ = yc - 0.5 * o_.corridor_width_m;
    yc1_ = yc + 0.5 * o_.corridor_width_m;
    if (o_.floors >= 2) {
      stairs_ = stairGeometry(o_);
      hall_x1_ = xi0_ + 2 * stairs_.landing + stairs_.run;
      rooms_x0_ = hall_x1_ + t;
      layout_.step_rise_m = stairs_.rise;
      layout_.step_tread_m = kTread_m;
    } else {
      hall_x1_ = rooms_x0_ = xi0_;
    }

    const double ceiling = uniform(0.6, 0.8);
    for (int f = 0; f <= o_.floors; ++f) {  // f == floors: the roof
      const double top = f * o_.floor_height_m;
      world_.fillBox(box(0, 0, top - o_.slab_thickness_m, o_.size_x_m, o_.size_y_m, top), float(ceiling));
    }
    const double z_lo = -o_.slab_thickness_m, z_hi = o_.floors * o_.floor_height_m;
    const float outer = float(uniform(0.35, 0.6));
    world_.fillBox(box(0, 0, z_lo, o_.size_x_m, w, z_hi), outer);
    world_.fillBox(box(0, o_.size_y_m - w, z_lo, o_.size_x_m, o_.size_y_m, z_hi), outer);
    world_.fillBox(box(0, 0, z_lo, w, o_.size_y_m, z_hi), outer);
    world_.fillBox(box(o_.size_x_m - w, 0, z_lo, o_.size_x_m, o_.size_y_m, z_hi), outer);

    for (int f = 0; f < o_.floors; ++f) buildStorey(f);
    for (int f = 0; f + 1 < o_.floors; ++f) buildFlight(f);
    return std::move(world_);
  }

 private:
  double uniform(double a, double b) { return a < b ? std::uniform_real_distribution<double>(a, b)(rng_) : a; }
  int uniformInt(int a, int b) { return std::uniform_int_distribution<int>(a, b)(rng_); }

  /// Paints the top voxel layer of the slab under a rectangle (the walking surface).
  void floorLayer(const Rect& r, double z, double reflectivity) {
    world_.fillBox(box(r.x0, r.y0, z - o_.voxel_m, r.x1, r.y1, z), float(reflectivity));
  }

  void wall(const Box& b, float reflectivity) {
    world_.fillBox(b, reflectivity);
    layout_.walls.push_back(b);
  }

  void door(const Box& b) {
    world_.clearBox(b);
    layout_.doors.push_back(b);
  }

  void buildStorey(int f) {
    const double z = f * o_.floor_height_m, ceiling = (f + 1) * o_.floor_height_m - o_.slab_thickness_m;
    const double t = o_.inner_wall_m, dw = o_.door_width_m, dh = o_.door_height_m;

    // Corridor, stair hall and their walls.
    const Rect corridor{hall_x1_, yc0_, xi1_, yc1_};
    floorLayer(corridor, z, uniform(0.2, 0.4));
    layout_.corridors.push_back(box(corridor.x0, corridor.y0, z, corridor.x1, corridor.y1, ceiling));
    if (o_.floors >= 2) {
      floorLayer({xi0_, yi0_, hall_x1_, yi1_}, z, uniform(0.2, 0.4));
      layout_.stair_halls.push_back(box(xi0_, yi0_, z, hall_x1_, yi1_, ceiling));
      const float hall_wall = float(uniform(0.45, 0.8));
      wall(box(hall_x1_, yi0_, z, rooms_x0_, yc0_, ceiling), hall_wall);
      wall(box(hall_x1_, yc1_, z, rooms_x0_, yi1_, ceiling), hall_wall);
    }
    wall(box(hall_x1_, yc0_ - t, z, xi1_, yc0_, ceiling), float(uniform(0.45, 0.8)));
    wall(box(hall_x1_, yc1_, z, xi1_, yc1_ + t, ceiling), float(uniform(0.45, 0.8)));

    // Rooms in the south (y < corridor) and north strips.
    const double length = xi1_ - rooms_x0_;
    const int fit = roomsPerStrip(o_, length);
    const int n = std::min(uniformInt(o_.min_rooms, o_.max_rooms), 2 * fit);
    const int south = n / 2 + (n % 2 == 1 ? uniformInt(0, 1) : 0);
    std::vector<Rect> door_zones;  // furniture-free approaches, per storey
    std::vector<Rect> rooms;
    for (int side = 0; side < 2; ++side) {
      const int count = side == 0 ? south : n - south;
      const double y0 = side == 0 ? yi0_ : yc1_ + t, y1 = side == 0 ? yc0_ - t : yi1_;
      // Widths: the minimum plus random shares of the slack.
      std::vector<double> share(count);
      double share_sum = 0.0;
      for (double& s : share) share_sum += (s = uniform(0.2, 1.0));
      const double slack = length - (count - 1) * t - count * o_.min_room_width_m;
      double x = rooms_x0_;
      for (int i = 0; i < count; ++i) {
        const double x1 = i + 1 == count ? xi1_ : x + o_.min_room_width_m + slack * share[i] / share_sum;
        const Rect room{x, y0, x1, y1};
        rooms.push_back(room);
        floorLayer(room, z, uniform(0.1, 0.35));
        layout_.rooms.push_back(box(room.x0, room.y0, z, room.x1, room.y1, ceiling));
        // Door to the corridor.
        const double xc = uniform(x + 0.3 + 0.5 * dw, x1 - 0.3 - 0.5 * dw);
        const double wy0 = side == 0 ? yc0_ - t : yc1_, wy1 = wy0 + t;
        door(box(xc - 0.5 * dw, wy0 - 0.01, z, xc + 0.5 * dw, wy1 + 0.01, z + dh));
        door_zones.push_back(side == 0 ? Rect{xc - 0.5 * dw - 0.3, y1 - kDoorApproach_m, xc + 0.5 * dw + 0.3, y1}
                                       : Rect{xc - 0.5 * dw - 0.3, y0, xc + 0.5 * dw + 0.3, y0 + kDoorApproach_m});
        if (i + 1 < count) {
          // Partition to the next room, sometimes with a door through it.
          wall(box(x1, y0, z, x1 + t, y1, ceiling), float(uniform(0.45, 0.8)));
          if (uniform(0.0, 1.0) < 0.35) {
            const double yd = uniform(y0 + 0.3 + 0.5 * dw, y1 - 0.3 - 0.5 * dw);
            door(box(x1 - 0.01, yd - 0.5 * dw, z, x1 + t + 0.01, yd + 0.5 * dw, z + dh));
            door_zones.push_back({x1 - kDoorApproach_m, yd - 0.5 * dw - 0.3, x1 + t + kDoorApproach_m,
                                  yd + 0.5 * dw + 0.3});
          }
        }
        x = x1 + t;
      }
    }
    for (const Rect& room : rooms) furnish(room, z, door_zones);
    placeMarkers(z);
  }

  /// Tables, shelves and cabinets, kept off door approaches and apart from each other.
  void furnish(const Rect& room, double z, const std::vector<Rect>& door_zones) {
    std::vector<Rect> placed;
    const int count = uniformInt(0, o_.max_furniture_per_room);
    for (int piece = 0; piece < count; ++piece) {
      const double kind = uniform(0.0, 1.0);
      for (int attempt = 0; attempt < 30; ++attempt) {
        Rect r;
        int back = -1;  // wall the piece stands against: 0 y0, 1 y1, 2 x0, 3 x1
        double length, depth, height;
        if (kind < 0.35) {  // table, free-standing
          length = uniform(1.2, 1.8);
          depth = uniform(0.7, 0.9);
          height = uniform(0.72, 0.78);
          const double x = uniform(room.x0 + 0.5, room.x1 - 0.5 - length);
          const double y = uniform(room.y0 + 0.5, room.y1 - 0.5 - depth);
          r = {x, y, x + length, y + depth};
        } else {  // shelf or cabinet against a wall
          const bool shelf = kind < 0.7;
          length = shelf ? uniform(0.8, 1.6) : uniform(0.5, 1.2);
          depth = shelf ? uniform(0.3, 0.4) : uniform(0.4, 0.6);
          height = shelf ? uniform(1.6, 2.1) : uniform(0.8, 1.1);
          back = uniformInt(0, 3);
          if (back < 2) {
            const double x = uniform(room.x0, room.x1 - length);
            r = back == 0 ? Rect{x, room.y0, x + length, room.y0 + depth} : Rect{x, room.y1 - depth, x + length, room.y1};
          } else {
            const double y = uniform(room.y0, room.y1 - length);
            r = back == 2 ? Rect{room.x0, y, room.x0 + depth, y + length} : Rect{room.x1 - depth, y, room.x1, y + length};
          }
        }
        if (r.x0 < room.x0 || r.x1 > room.x1 || r.y0 < room.y0 || r.y1 > room.y1) continue;
        const auto blocked = [&](const std::vector<Rect>& others, double gap) {
          return std::any_of(others.begin(), others.end(), [&](const Rect& o) { return r.overlaps(o, gap); });
        };
        if (blocked(door_zones, 0.0) || blocked(placed, kFurnitureGap_m)) continue;
        placed.push_back(r);
        const float rho = float(uniform(0.05, 0.9));
        if (kind < 0.35) {
          buildTable(r, z, height, rho);
        } else if (kind < 0.7) {
          buildShelf(r, back, z, height, rho);
        } else {
          world_.fillBox(box(r.x0, r.y0, z, r.x1, r.y1, z + height), rho);
        }
        layout_.furniture.push_back(box(r.x0, r.y0, z, r.x1, r.y1, z + height));
        break;
      }
    }
  }

  /// Thin parts are at least a voxel thick so that coarse worlds keep them
  /// (a box thinner than a voxel may select no voxel centre).
  double board() const { return std::max(kBoard_m, o_.voxel_m); }

  void buildTable(const Rect& r, double z, double height, float rho) {
    const double top = std::max(kTableTop_m, o_.voxel_m), leg = board(), inset = 0.05;
    world_.fillBox(box(r.x0, r.y0, z + height - top, r.x1, r.y1, z + height), rho);
    for (int corner = 0; corner < 4; ++corner) {
      const double x = corner & 1 ? r.x1 - inset - leg : r.x0 + inset;
      const double y = corner & 2 ? r.y1 - inset - leg : r.y0 + inset;
      world_.fillBox(box(x, y, z, x + leg, y + leg, z + height - top), rho);
    }
  }

  /// Open shelf: back panel, two side panels and boards every ~0.4 m.
  void buildShelf(const Rect& r, int back, double z, double height, float rho) {
    const double top = z + height, b = board();
    switch (back) {
      case 0: world_.fillBox(box(r.x0, r.y0, z, r.x1, r.y0 + b, top), rho); break;
      case 1: world_.fillBox(box(r.x0, r.y1 - b, z, r.x1, r.y1, top), rho); break;
      case 2: world_.fillBox(box(r.x0, r.y0, z, r.x0 + b, r.y1, top), rho); break;
      default: world_.fillBox(box(r.x1 - b, r.y0, z, r.x1, r.y1, top), rho); break;
    }
    if (back < 2) {  // length along x: sides at both x ends
      world_.fillBox(box(r.x0, r.y0, z, r.x0 + b, r.y1, top), rho);
      world_.fillBox(box(r.x1 - b, r.y0, z, r.x1, r.y1, top), rho);
    } else {
      world_.fillBox(box(r.x0, r.y0, z, r.x1, r.y0 + b, top), rho);
      world_.fillBox(box(r.x0, r.y1 - b, z, r.x1, r.y1, top), rho);
    }
    const int boards = std::max(2, static_cast<int>(std::round(height / 0.4)) + 1);
    for (int i = 0; i < boards; ++i) {
      const double zb = z + i * (height - b) / (boards - 1);
      world_.fillBox(box(r.x0, r.y0, zb, r.x1, r.y1, zb + b), rho);
    }
  }

  /// Retro-reflective tape strips on the corridor walls, clear of doors.
  void placeMarkers(double z) {
    const double v = o_.voxel_m, strip = std::max(0.05, v);
    const int per_side = std::max(1, static_cast<int>(std::lround((xi1_ - hall_x1_) / 4.0)));
    for (int side = 0; side < 2; ++side) {
      const double y0 = side == 0 ? yc0_ - v : yc1_, y1 = y0 + v;
      for (int i = 0; i < per_side; ++i) {
        for (int attempt = 0; attempt < 10; ++attempt) {
          const double len = uniform(0.3, 1.0), x = uniform(hall_x1_ + 0.2, xi1_ - 0.2 - len);
          const double zm = z + uniform(0.8, 1.8);
          const Box b = box(x, y0, zm, x + len, y1, zm + strip);
          const bool on_door = std::any_of(layout_.doors.begin(), layout_.doors.end(), [&](const Box& d) {
            return d.intersects(Box(b.min() - Eigen::Vector3d::Constant(0.1), b.max() + Eigen::Vector3d::Constant(0.1)));
          });
          if (on_door) continue;
          world_.fillBox(b, float(uniform(0.9, 1.0)));
          layout_.markers.push_back(b);
          break;
        }
      }
    }
  }

  /// Flight from storey f to f + 1: even flights climb +x in the south lane,
  /// odd ones −x in the north lane (switchback), each under an opening in the
  /// slab above, guarded by a railing on the upper storey.
  void buildFlight(int f) {
    const double z = f * o_.floor_height_m, z_up = z + o_.floor_height_m;
    const bool even = f % 2 == 0;
    const double y0 = even ? yi0_ : yi1_ - o_.stair_width_m, y1 = y0 + o_.stair_width_m;
    const double x0 = xi0_ + stairs_.landing, x1 = x0 + stairs_.run;
    world_.clearBox(box(x0, y0, z_up - o_.slab_thickness_m, x1, y1, z_up));
    const float rho = float(uniform(0.25, 0.45));
    for (int k = 0; k < stairs_.steps; ++k) {
      const double top = z + (k + 1) * stairs_.rise;
      world_.fillBox(even ? box(x0 + k * kTread_m, y0, z, x1, y1, top) : box(x0, y0, z, x1 - k * kTread_m, y1, top), rho);
    }
    layout_.stair_flights.push_back(box(x0, y0, z, x1, y1, z_up));
    // Railing along the inner edge of the opening and across its far end.
    const float metal = float(uniform(0.6, 0.9));
    const double rail = 1.0, post = board();
    const double ry0 = even ? y1 : y0 - post;
    world_.fillBox(box(x0, ry0, z_up, x1, ry0 + post, z_up + rail), metal);
    const double rx0 = even ? x0 - post : x1;
    world_.fillBox(box(rx0, y0, z_up, rx0 + post, y1, z_up + rail), metal);
  }

  const BuildingOptions& o_;
  std::mt19937_64 rng_;
  BuildingLayout& layout_;
  VoxelWorld world_;
  StairGeometry stairs_{0, 0.0, 0.0, 0.0};
  double xi0_ = 0, xi1_ = 0, yi0_ = 0, yi1_ = 0;  ///< interior of the outer walls
  double yc0_ = 0, yc1_ = 0;                      ///< corridor edges
  double hall_x1_ = 0, rooms_x0_ = 0;             ///< east end of the stair hall, west end of the rooms
};

}  // namespace

void BuildingOptions::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("BuildingOptions: " + what); };
  auto finite = [](double v) { return std::isfinite(v); };
  if (!(voxel_m > 0.0 && voxel_m <= 0.5)) fail("voxel_m must be in (0, 0.5]");
  if (floors < 1 || floors > 10) fail("floors must be in [1, 10]");
  if (!(slab_thickness_m >= voxel_m && slab_thickness_m <= 1.0)) fail("slab_thickness_m must be in [voxel_m, 1]");
  if (!(door_height_m >= 1.8) || !finite(door_height_m)) fail("door_height_m must be ≥ 1.8");
  if (!(floor_height_m >= door_height_m + slab_thickness_m + 0.3) || !finite(floor_height_m)) {
    fail("floor_height_m must be ≥ door_height_m + slab_thickness_m + 0.3");
  }
  if (!(outer_wall_m >= voxel_m) || !(inner_wall_m >= voxel_m) || !finite(outer_wall_m) || !finite(inner_wall_m)) {
    fail("wall thicknesses must be ≥ voxel_m");
  }
  if (!(corridor_width_m >= 1.2) || !finite(corridor_width_m)) fail("corridor_width_m must be ≥ 1.2");
  if (!(door_width_m >= 0.6) || !finite(door_width_m)) fail("door_width_m must be ≥ 0.6");
  if (!(min_room_width_m >= door_width_m + 0.6) || !finite(min_room_width_m)) {
    fail("min_room_width_m must be ≥ door_width_m + 0.6");
  }
  if (min_rooms < 2 || max_rooms < min_rooms) fail("need 2 ≤ min_rooms ≤ max_rooms");
  if (max_furniture_per_room < 0) fail("max_furniture_per_room must be ≥ 0");
  if (!(stair_width_m >= 0.8) || !finite(stair_width_m)) fail("stair_width_m must be ≥ 0.8");
  if (!finite(size_x_m) || !finite(size_y_m)) fail("footprint must be finite");
  const double inner_y = size_y_m - 2 * outer_wall_m;
  if (!(inner_y >= corridor_width_m + 2 * (inner_wall_m + min_room_width_m))) {
    fail("size_y_m too small for the corridor and two rows of rooms at least min_room_width_m deep");
  }
  double rooms_x0 = outer_wall_m;
  if (floors >= 2) {
    if (!(inner_y >= 2 * stair_width_m + 1.0)) fail("size_y_m too small for two stair lanes and a 1 m gap");
    const StairGeometry s = stairGeometry(*this);
    rooms_x0 += 2 * s.landing + s.run + inner_wall_m;
  }
  const double strip = size_x_m - outer_wall_m - rooms_x0;
  if (2 * roomsPerStrip(*this, strip) < min_rooms) {
    fail("size_x_m too small for min_rooms rooms of min_room_width_m" +
         std::string(floors >= 2 ? " next to the stair hall" : ""));
  }
}

VoxelWorld makeBuilding(const BuildingOptions& options, uint64_t seed, BuildingLayout* layout) {
  options.validate();
  BuildingLayout local;
  BuildingLayout& out = layout != nullptr ? *layout : local;
  out = BuildingLayout{};
  return Builder(options, seed, out).build();
}

}  // namespace rmap::sim
