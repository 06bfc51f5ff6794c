// rmap import: an OctoMap (.bt or .ot) into a named map of the server.
#include <iostream>
#include <memory>

#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/map_server.h"

namespace rmap::cli {

namespace {

struct ImportOptions {
  MapServerOptions server;
  std::string file;
  bool replace = false;
  bool json = false;
};

}  // namespace

void addImportCommand(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<ImportOptions>();
  CLI::App* command = app.add_subcommand("import", "load an OctoMap (.bt or .ot) into a map of the server");
  o->server.timeout_s = 300.0;
  o->server.addTo(*command);
  command->add_option("file", o->file, "FILE.bt or FILE.ot (OcTree; .ot also ColorOcTree, OcTreeStamped)")
      ->required()
      ->check(CLI::ExistingFile);
  command->add_flag("--replace", o->replace, "replace the 3D content of a map that is not empty (else refused)");
  command->add_flag("--json", o->json, "print the server's answer as JSON");
  command->callback([o, &exit_code] {
    exit_code = runCommand("import", [&] {
      const std::string bytes = readFile(o->file);
      const std::unique_ptr<client::HttpClient> http = o->server.connect();
      const client::HttpResponse& r = requireOk(
          http->post(o->server.mapPath(std::string(":import?replace=") + (o->replace ? "true" : "false")), bytes,
                     "application/octet-stream"),
          "import");
      const nlohmann::json answer = nlohmann::json::parse(r.body);
      if (o->json) {
        std::cout << answer.dump() << "\n";
        return;
      }
      std::cout << "imported " << o->file << " (" << answer["tree_id"].get<std::string>() << ", "
                << answer["leaves"].get<size_t>() << " leaves) into " << (answer["created"].get<bool>() ? "new " : "")
                << "map " << o->server.map << ": " << answer["map"]["cuboids"].get<uint64_t>() << " cuboids, "
                << answer["map"]["known_cells"].get<uint64_t>() << " known cells at "
                << answer["map"]["resolution_m"].get<double>() << " m\n";
    });
  });
}

}  // namespace rmap::cli
