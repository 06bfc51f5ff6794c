// `rmap export` against a real rmapd: a map fed with simulated lidar clouds and 2D laser
// scans, exported in every format and read back — the .bt by liboctomap (occupancy equal to
// the server's answers), the PLY by its vertex and face counts against the server's cuboids,
// the map_server PGM + YAML by a parser, the reflectivity PNG by libpng.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <map>
#include <random>
#include <sstream>

#include "api_helpers.h"
#include "image_files.h"
#include "client/laser2d_robot.h"
#include "rmap_cli.h"
#include "laser_walker.h"
#include "rmapd_process.h"
#include "scene_clouds.h"
#include "sim/building.h"
#include "sim/trajectory.h"

namespace rmap::testing {
namespace {

/// "element <name> <count>" of a PLY header; -1 when absent.
long plyCount(const std::string& ply, const std::string& element) {
  const std::string key = "\nelement " + element + " ";
  const size_t at = ply.find(key);
  return at == std::string::npos ? -1 : std::stol(ply.substr(at + key.size()));
}

/// A binary PGM: size, maxval and pixels.
struct Pgm {
  int width = 0, height = 0, maxval = 0;
  std::string pixels;
};

Pgm parsePgm(const std::string& bytes) {
  std::istringstream in(bytes);
  std::string magic;
  Pgm pgm;
  in >> magic >> pgm.width >> pgm.height >> pgm.maxval;
  in.get();  // the single whitespace after maxval
  if (magic != "P5" || !in) throw std::runtime_error("not a binary PGM");
  pgm.pixels = bytes.substr(static_cast<size_t>(in.tellg()));
  return pgm;
}

class Export : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir("rmap-export");
    rmapd_ = new RmapdProcess(dir_->path() / "data");
    const client::SimScene scene = client::makeSimScene(4);
    streamAll(rmapd_->wsUrl(), "lidar", "lab", sceneClouds(scene, 6, 3));
    // A 2D laser robot on a map of its own: the 2D layers.
    sim::BuildingOptions building;
    building.max_furniture_per_room = 1;
    sim::BuildingLayout layout;
    sim::VoxelWorld world = sim::makeBuilding(building, 3, &layout);
    client::extendMarkersToLaserPlane(world, layout, building.floor_height_m, kWalkerLaserHeight_m);
    constexpr int kScans = 160;
    client::Laser2dRobot walker = buildingWalker(world, kScans);
    std::vector<v1::RobotMessage> scans;
    for (int k = 0; k < kScans; ++k) {
      v1::RobotMessage m;
      *m.mutable_scan() = walker.next().scan;
      m.mutable_scan()->set_stamp_ns(static_cast<int64_t>(k) * 100'000'000);
      scans.push_back(std::move(m));
    }
    const v1::SensorDescription sensor = walker.sensor();
    streamAll(rmapd_->wsUrl(), "walker", "floor", scans, &sensor);
    client::HttpClient http(rmapd_->httpUrl());
    waitForIdleFusion(http, "lab");
  }
  static void TearDownTestSuite() {
    delete rmapd_;
    delete dir_;
  }

  std::string common(const std::string& map) const { return "export --server " + rmapd_->httpUrl() + " --map " + map; }

  static TempDir* dir_;
  static RmapdProcess* rmapd_;
  TempDir scratch_{"rmap-export-out"};
};

TempDir* Export::dir_ = nullptr;
RmapdProcess* Export::rmapd_ = nullptr;

TEST_F(Export, OctomapReadsTheBtWithTheServersOccupancy) {
  const std::filesystem::path file = scratch_.path() / "lab.bt";
  const CliRun run = runRmap(common("lab") + " --format bt --output '" + file.string() + "'", scratch_.path());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(file.string())) << "liboctomap could not read the export";
  client::HttpClient http(rmapd_->httpUrl(), {}, kWholeMapRequestTimeout);
  const nlohmann::json info = getJson(http, "/v1/maps/lab");
  EXPECT_DOUBLE_EQ(tree.getResolution(), info["resolution_m"].get<double>());
  // Cells the map knows add up to the tree's leaves.
  uint64_t tree_cells = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    const uint64_t size = uint64_t{1} << (16 - it.getDepth());
    tree_cells += size * size * size;
  }
  EXPECT_EQ(tree_cells, info["known_cells"].get<uint64_t>());
  // Sample points: a corner cell of every cuboid and random points over the bounds (unknown space too).
  const double r = info["resolution_m"].get<double>();
  std::vector<Eigen::Vector3d> points;
  for (const nlohmann::json& c : allCuboids(http, "lab")) {
    points.emplace_back(c["min"][0].get<double>() + r / 2, c["min"][1].get<double>() + r / 2,
                        c["min"][2].get<double>() + r / 2);
  }
  std::mt19937 rng(7);
  for (int i = 0; i < 3000; ++i) {
    // Cell centres: float and double arithmetic agree on their cell.
    Eigen::Vector3d p;
    for (int a = 0; a < 3; ++a) {
      std::uniform_real_distribution<double> u(info["bounds"]["min"][a].get<double>() - 1.0,
                                               info["bounds"]["max"][a].get<double>() + 1.0);
      p[a] = (std::floor(u(rng) / r) + 0.5) * r;
    }
    points.push_back(p);
  }
  const v1::OccupancyBatchResponse answers = batchQuery(http, "lab", points);
  ASSERT_EQ(static_cast<size_t>(answers.states_size()), points.size());
  size_t occupied = 0, free = 0, unknown = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    const octomap::OcTreeNode* node = tree.search(points[i].x(), points[i].y(), points[i].z());
    const v1::CellState octomap_state = !node ? v1::UNKNOWN : tree.isNodeOccupied(node) ? v1::OCCUPIED : v1::FREE;
    ASSERT_EQ(octomap_state, answers.states(static_cast<int>(i))) << "point " << points[i].transpose();
    (octomap_state == v1::OCCUPIED ? occupied : octomap_state == v1::FREE ? free : unknown) += 1;
  }
  EXPECT_GT(occupied, 100u);
  EXPECT_GT(free, 100u);
  EXPECT_GT(unknown, 10u);
  std::printf("[ bt ] %zu points agree (%zu occupied, %zu free, %zu unknown), %lu bytes\n", points.size(), occupied,
              free, unknown, static_cast<unsigned long>(std::filesystem::file_size(file)));
}

TEST_F(Export, PlyHoldsOneVertexPerCuboidOrABoxPerCuboid) {
  client::HttpClient http(rmapd_->httpUrl(), {}, kWholeMapRequestTimeout);
  const std::vector<nlohmann::json> cuboids = allCuboids(http, "lab");
  const long occupied = std::count_if(cuboids.begin(), cuboids.end(),
                                      [](const nlohmann::json& c) { return c["state"] == "occupied"; });
  ASSERT_GT(occupied, 100);
  const std::filesystem::path file = scratch_.path() / "lab.ply";
  const auto exportPly = [&](const std::string& options) {
    const CliRun run = runRmap(common("lab") + " --format ply --output '" + file.string() + "' " + options,
                               scratch_.path());
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return fileText(file);
  };
  std::string ply = exportPly("");
  EXPECT_EQ(plyCount(ply, "vertex"), occupied);
  EXPECT_EQ(plyCount(ply, "face"), -1);
  ply = exportPly("--ply-cuboids all");
  EXPECT_EQ(plyCount(ply, "vertex"), static_cast<long>(cuboids.size()));
  ply = exportPly("--ply-mode mesh");
  EXPECT_EQ(plyCount(ply, "vertex"), 8 * occupied);
  EXPECT_EQ(plyCount(ply, "face"), 6 * occupied);
  // Exactly the bytes those counts take: 4 floats per vertex, a count and 4 indices per quad.
  const size_t header = ply.find("end_header\n") + 11;
  EXPECT_EQ(ply.size() - header, static_cast<size_t>(8 * occupied * 16 + 6 * occupied * 17));
}

TEST_F(Export, MapServerPgmAndYamlNameEachOther) {
  const std::filesystem::path file = scratch_.path() / "floor.pgm";
  const CliRun run = runRmap(common("floor") + " --format pgm --output '" + file.string() + "'", scratch_.path());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const Pgm pgm = parsePgm(fileText(file));
  EXPECT_EQ(pgm.maxval, 255);
  ASSERT_GT(pgm.width, 20);
  ASSERT_GT(pgm.height, 20);
  ASSERT_EQ(pgm.pixels.size(), static_cast<size_t>(pgm.width) * pgm.height);
  size_t occupied = 0, free = 0;
  for (const char p : pgm.pixels) {
    const auto v = static_cast<uint8_t>(p);
    ASSERT_TRUE(v == 0 || v == 254 || v == 205) << int{v};
    occupied += v == 0;
    free += v == 254;
  }
  EXPECT_GT(occupied, 50u);
  EXPECT_GT(free, 500u);
  const std::map<std::string, std::string> yaml = parseYaml(fileText(scratch_.path() / "floor.yaml"));
  EXPECT_EQ(yaml.at("image"), "floor.pgm");
  client::HttpClient http(rmapd_->httpUrl());
  const nlohmann::json layers = getJson(http, "/v1/maps/floor/layers");
  EXPECT_DOUBLE_EQ(std::stod(yaml.at("resolution")), layers["resolution_m"].get<double>());
  double origin_x = 0, origin_y = 0;
  ASSERT_EQ(std::sscanf(yaml.at("origin").c_str(), "[%lf, %lf", &origin_x, &origin_y), 2);
  EXPECT_NEAR(origin_x, layers["known_bounds"]["min"][0].get<double>(), 1e-9);
  EXPECT_NEAR(origin_y, layers["known_bounds"]["min"][1].get<double>(), 1e-9);
  EXPECT_EQ(yaml.at("mode"), "trinary");
  // The pixels are the server's.
  EXPECT_EQ(fileText(file), http.get("/v1/maps/floor/grid2d.pgm").body);
}

TEST_F(Export, ReflectivityPngCoversTheSameCellsAsThePgm) {
  const std::filesystem::path png = scratch_.path() / "floor-reflectivity.png";
  const std::filesystem::path pgm = scratch_.path() / "floor.pgm";
  ASSERT_EQ(runRmap(common("floor") + " --format reflectivity --output '" + png.string() + "'", scratch_.path()).exit_code, 0);
  ASSERT_EQ(runRmap(common("floor") + " --format pgm --output '" + pgm.string() + "'", scratch_.path()).exit_code, 0);
  const GreyAlpha image = decodePng(fileText(png));
  const Pgm grid = parsePgm(fileText(pgm));
  EXPECT_EQ(image.width, grid.width);
  EXPECT_EQ(image.height, grid.height);
  // Reflectivity is fused where beams ended: mostly on the occupied (black) cells of the PGM.
  size_t on_walls = 0, elsewhere = 0;
  for (size_t i = 0; i < grid.pixels.size(); ++i) {
    if (image.pixels[2 * i + 1] != 255) continue;
    (static_cast<uint8_t>(grid.pixels[i]) == 0 ? on_walls : elsewhere) += 1;
  }
  EXPECT_GT(on_walls, 500u);
  EXPECT_GT(on_walls, elsewhere);
  // Pixel for pixel the native-zoom tiles (one cell per pixel): row 0 is the +y edge.
  client::HttpClient http(rmapd_->httpUrl());
  const nlohmann::json layers = getJson(http, "/v1/maps/floor/layers");
  const double r = layers["resolution_m"].get<double>();
  const int min_x = static_cast<int>(std::lround(layers["known_bounds"]["min"][0].get<double>() / r));
  const int max_y = static_cast<int>(std::lround(layers["known_bounds"]["max"][1].get<double>() / r)) - 1;
  LayerCells tiles(http, "floor", "reflectivity");
  size_t compared = 0;
  for (int row = 0; row < image.height; ++row) {
    for (int col = 0; col < image.width; ++col) {
      const size_t here = 2 * static_cast<size_t>(row * image.width + col);
      const auto [grey, alpha] = tiles.at(min_x + col, max_y - row);
      ASSERT_EQ(image.pixels[here], grey) << "pixel " << col << "," << row;
      ASSERT_EQ(image.pixels[here + 1], alpha) << "pixel " << col << "," << row;
      ++compared;
    }
  }
  std::printf("[ reflectivity ] %d x %d px, %zu on walls, %zu elsewhere; %zu pixels equal the tiles'\n", image.width,
              image.height, on_walls, elsewhere, compared);
}

TEST_F(Export, ClearErrorsAndNoFileForBadRequests) {
  const std::filesystem::path file = scratch_.path() / "nothing.bt";
  CliRun run = runRmap(common("nope") + " --format bt --output '" + file.string() + "'", scratch_.path());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("map_not_found"), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(file));
  // The lidar map has no 2D layer.
  run = runRmap(common("lab") + " --format pgm --output '" + (scratch_.path() / "lab.pgm").string() + "'",
                scratch_.path());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("layer_not_found"), std::string::npos) << run.err;
  run = runRmap(common("lab") + " --format jpeg --output x.jpg", scratch_.path());
  EXPECT_EQ(run.exit_code, 2) << run.err;
}

}  // namespace
}  // namespace rmap::testing
