// rmap export: a map's 3D layer as an OctoMap .bt or a PLY, its 2D occupancy layer as a ROS
// map_server PGM + YAML, its reflectivity layer as a PNG.
#include <iostream>
#include <memory>

#include "cli/box_pages.h"
#include "cli/commands.h"
#include "cli/cuboid_ply.h"
#include "cli/map_server.h"
#include "cli/map_server_yaml.h"

namespace rmap::cli {

namespace {

/// Tries at fetching the PGM and the YAML of one grid version while the map grows.
constexpr int kPgmAttempts = 5;

struct ExportOptions {
  MapServerOptions server;
  std::string format;
  std::string output;
  std::string ply_mode = "centres";
  std::string ply_cuboids = "occupied";
  size_t page_size = 10'000;
};

/// What went to disk, for the summary line.
struct Written {
  std::string what;
  size_t bytes = 0;
};

Written exportBody(const ExportOptions& o, client::HttpClient& http, const std::string& suffix,
                   const std::string& what) {
  const client::HttpResponse& r = requireOk(http.get(o.server.mapPath(suffix)), what);
  writeFileAtomically(o.output, r.body);
  return {what, r.body.size()};
}

Written exportPly(const ExportOptions& o, client::HttpClient& http) {
  const nlohmann::json map = nlohmann::json::parse(requireOk(http.get(o.server.mapPath()), "map").body);
  std::vector<Cuboid> cuboids;
  size_t stored = 0;
  if (map["bounds"].is_object()) {
    const auto corner = [&](const char* key) {
      return std::array<double, 3>{map["bounds"][key][0].get<double>(), map["bounds"][key][1].get<double>(),
                                   map["bounds"][key][2].get<double>()};
    };
    const bool all = o.ply_cuboids == "all";
    stored = forEachBoxCuboid(http, o.server.mapPath(), corner("min"), corner("max"), o.page_size,
                              [&](const nlohmann::json& c) {
                                if (!all && c["state"] != "occupied") return;
                                Cuboid& out = cuboids.emplace_back();
                                for (int a = 0; a < 3; ++a) {
                                  out.min_m[a] = c["min"][a].get<double>();
                                  out.max_m[a] = c["max"][a].get<double>();
                                }
                                out.probability = c["probability"].get<float>();
                              });
  }
  const std::string ply = o.ply_mode == "mesh" ? cuboidMeshPly(cuboids) : cuboidCentresPly(cuboids);
  writeFileAtomically(o.output, ply);
  return {"PLY (" + o.ply_mode + ") of " + std::to_string(cuboids.size()) + " " + o.ply_cuboids + " cuboids of " +
              std::to_string(stored),
          ply.size()};
}

/// The PGM and YAML of one grid version (their ETags agree), YAML naming the PGM file.
Written exportPgm(const ExportOptions& o, client::HttpClient& http) {
  for (int attempt = 1;; ++attempt) {
    const client::HttpResponse pgm = requireOk(http.get(o.server.mapPath("/grid2d.pgm")), "map_server PGM");
    const client::HttpResponse yaml = requireOk(http.get(o.server.mapPath("/grid2d.yaml")), "map_server YAML");
    const std::string version = layerVersionOf(pgm.header("etag"));
    if (version.empty() || version != layerVersionOf(yaml.header("etag"))) {
      if (attempt < kPgmAttempts) continue;
      throw CommandError("the 2D map kept changing between its PGM and its YAML; try again when it is still");
    }
    const std::filesystem::path pgm_path(o.output);
    const std::filesystem::path yaml_path = yamlPathFor(pgm_path);
    writeFileAtomically(pgm_path, pgm.body);
    writeFileAtomically(yaml_path, withImage(yaml.body, pgm_path.filename().string()));
    return {"map_server PGM (and " + yaml_path.string() + ")", pgm.body.size()};
  }
}

}  // namespace

void addExportCommand(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<ExportOptions>();
  CLI::App* command = app.add_subcommand("export", "write a map to a file: OctoMap .bt, PLY, map_server PGM+YAML, PNG");
  o->server.timeout_s = 300.0;
  o->server.addTo(*command);
  command->add_option("--format", o->format,
                      "bt: the 3D map as an OctoMap binary tree; ply: its cuboids; pgm: the 2D occupancy layer for "
                      "ROS map_server (FILE, and its .yaml beside it); reflectivity: the 2D reflectivity layer as a PNG")
      ->required()
      ->check(CLI::IsMember({"bt", "ply", "pgm", "reflectivity"}));
  command->add_option("--output", o->output, "FILE to write")->required();
  command->add_option("--ply-mode", o->ply_mode, "centres: a vertex per cuboid; mesh: each cuboid as a box of quads")
      ->check(CLI::IsMember({"centres", "mesh"}))
      ->capture_default_str();
  command->add_option("--ply-cuboids", o->ply_cuboids, "which cuboids go into the PLY")
      ->check(CLI::IsMember({"occupied", "all"}))
      ->capture_default_str();
  command->add_option("--page-size", o->page_size, "cuboids per box request when reading them for the PLY")
      ->check(CLI::Range(size_t{1}, size_t{100'000}))
      ->capture_default_str();
  command->callback([o, &exit_code] {
    exit_code = runCommand("export", [&] {
      const std::unique_ptr<client::HttpClient> http = o->server.connect();
      Written written;
      if (o->format == "bt") {
        written = exportBody(*o, *http, "/export.bt", "OctoMap .bt");
      } else if (o->format == "ply") {
        written = exportPly(*o, *http);
      } else if (o->format == "pgm") {
        written = exportPgm(*o, *http);
      } else {
        written = exportBody(*o, *http, "/layers/reflectivity.png", "reflectivity PNG");
      }
      std::cout << "wrote " << o->output << ": " << written.what << ", " << written.bytes << " bytes\n";
    });
  });
}

}  // namespace rmap::cli
