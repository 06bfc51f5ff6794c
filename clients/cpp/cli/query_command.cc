// rmap query: occupancy of a map at a point, in a box, or for a file of points.
#include <iostream>
#include <memory>

#include "cli/box_pages.h"
#include "cli/commands.h"
#include "cli/map_server.h"
#include "cli/query_points.h"
#include "rmap/v1/map_api.pb.h"

namespace rmap::cli {

namespace {

/// Points per occupancy:batch request: well inside the server's default limits.max_batch_points.
constexpr size_t kBatchPoints = 100'000;

struct QueryOptions {
  MapServerOptions server;
  std::string point;
  std::string box;
  std::string batch;
  bool json = false;
  size_t page_size = 10'000;
};

const char* stateName(v1::CellState state) {
  switch (state) {
    case v1::FREE: return "free";
    case v1::OCCUPIED: return "occupied";
    default: return "unknown";
  }
}

std::string cornerText(const nlohmann::json& xyz) {
  return numberText(xyz[0].get<double>()) + "," + numberText(xyz[1].get<double>()) + "," +
         numberText(xyz[2].get<double>());
}

void queryPoint(const QueryOptions& o, client::HttpClient& http) {
  const std::vector<double> p = parseNumbers(o.point, 3, "--point");
  const client::HttpResponse& r = requireOk(
      http.get(o.server.mapPath("/occupancy?x=" + numberText(p[0]) + "&y=" + numberText(p[1]) + "&z=" +
                                numberText(p[2]))),
      "point query");
  const nlohmann::json answer = nlohmann::json::parse(r.body);
  if (o.json) {
    std::cout << answer.dump() << "\n";
    return;
  }
  std::cout << answer["state"].get<std::string>() << " " << numberText(answer["probability"].get<double>());
  if (answer["cuboid"].is_object()) {
    std::cout << " cuboid " << cornerText(answer["cuboid"]["min"]) << " " << cornerText(answer["cuboid"]["max"]);
  }
  std::cout << "\n";
}

void queryBox(const QueryOptions& o, client::HttpClient& http) {
  const std::vector<double> b = parseNumbers(o.box, 6, "--box");
  nlohmann::json cuboids = nlohmann::json::array();
  forEachBoxCuboid(http, o.server.mapPath(), {b[0], b[1], b[2]}, {b[3], b[4], b[5]}, o.page_size,
                   [&](const nlohmann::json& c) {
                     if (o.json) {
                       cuboids.push_back(c);
                     } else {
                       std::cout << cornerText(c["min"]) << " " << cornerText(c["max"]) << " "
                                 << numberText(c["probability"].get<double>()) << " "
                                 << c["state"].get<std::string>() << "\n";
                     }
                   });
  if (o.json) std::cout << nlohmann::json{{"cuboids", std::move(cuboids)}}.dump() << "\n";
}

void queryBatch(const QueryOptions& o, client::HttpClient& http) {
  const std::vector<Eigen::Vector3d> points = parsePointLines(readFile(o.batch), o.batch);
  nlohmann::json states = nlohmann::json::array(), probabilities = nlohmann::json::array();
  for (size_t begin = 0; begin < points.size(); begin += kBatchPoints) {
    const size_t end = std::min(points.size(), begin + kBatchPoints);
    v1::OccupancyBatchRequest request;
    for (size_t i = begin; i < end; ++i) {
      for (int a = 0; a < 3; ++a) request.add_xyz_m(points[i][a]);
    }
    const client::HttpResponse& r = requireOk(
        http.post(o.server.mapPath("/occupancy:batch"), request.SerializeAsString(), "application/x-protobuf"),
        "batch query");
    v1::OccupancyBatchResponse answer;
    if (!answer.ParseFromString(r.body) || answer.states_size() != static_cast<int>(end - begin) ||
        answer.probabilities_size() != answer.states_size()) {
      throw CommandError("batch query: the server's answer does not hold one state per point");
    }
    for (int k = 0; k < answer.states_size(); ++k) {
      const Eigen::Vector3d& p = points[begin + static_cast<size_t>(k)];
      const char* state = stateName(answer.states(k));
      if (o.json) {
        states.push_back(state);
        probabilities.push_back(answer.probabilities(k));
      } else {
        std::cout << numberText(p.x()) << "," << numberText(p.y()) << "," << numberText(p.z()) << " " << state << " "
                  << numberText(answer.probabilities(k)) << "\n";
      }
    }
  }
  if (o.json) {
    nlohmann::json xyz = nlohmann::json::array();
    for (const Eigen::Vector3d& p : points) xyz.push_back({p.x(), p.y(), p.z()});
    std::cout << nlohmann::json{{"points", std::move(xyz)}, {"states", std::move(states)},
                                {"probabilities", std::move(probabilities)}}
                     .dump()
              << "\n";
  }
}

}  // namespace

void addQueryCommand(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<QueryOptions>();
  CLI::App* command = app.add_subcommand("query", "occupancy of a map at a point, in a box or for a file of points");
  o->server.addTo(*command);
  CLI::Option_group* what = command->add_option_group("what", "what to query (one of)");
  what->add_option("--point", o->point, "X,Y,Z in metres: the state of the cell holding it");
  what->add_option("--box", o->box, "MINX,MINY,MINZ,MAXX,MAXY,MAXZ in metres: every stored cuboid in the box");
  what->add_option("--batch", o->batch, "file of points, one 'x y z' or 'x,y,z' per line ('#' comments)")
      ->check(CLI::ExistingFile);
  what->require_option(1);
  command->add_flag("--json", o->json, "print the answers as JSON");
  command->add_option("--page-size", o->page_size, "cuboids per box request (at most the server's max_box_cuboids)")
      ->check(CLI::Range(size_t{1}, size_t{100'000}))
      ->capture_default_str();
  command->callback([o, &exit_code] {
    exit_code = runCommand("query", [&] {
      const std::unique_ptr<client::HttpClient> http = o->server.connect();
      if (!o->point.empty()) {
        queryPoint(*o, *http);
      } else if (!o->box.empty()) {
        queryBox(*o, *http);
      } else {
        queryBatch(*o, *http);
      }
    });
  });
}

}  // namespace rmap::cli
