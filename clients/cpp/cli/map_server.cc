#include "cli/map_server.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <iostream>
#include <sstream>

namespace rmap::cli {

void MapServerOptions::addTo(CLI::App& command) {
  command.add_option("--server", server_url, "rmapd's HTTP address, http://HOST:PORT or https://HOST:PORT")
      ->required();
  command.add_option("--map", map, "map name: 1..64 characters of [A-Za-z0-9._-]")
      ->required()
      ->check(CLI::Validator(
          [](const std::string& name) {
            const bool ok = !name.empty() && name.size() <= 64 &&
                            std::all_of(name.begin(), name.end(), [](unsigned char c) {
                              return std::isalnum(c) || c == '.' || c == '_' || c == '-';
                            });
            return ok ? std::string() : "map names are 1..64 characters of [A-Za-z0-9._-]";
          },
          "NAME"));
  command.add_option("--token", token, "bearer token (none in rmapd's loopback-only mode)")->envname("RMAP_TOKEN");
  command.add_option("--ca-file", ca_file, "https://: PEM CA certificates rmapd's certificate must chain to "
                     "(default: the system's trust store)");
  command.add_option("--timeout-s", timeout_s, "seconds to wait for each answer of the server")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

std::unique_ptr<client::HttpClient> MapServerOptions::connect() const {
  return std::make_unique<client::HttpClient>(
      server_url, token, std::chrono::milliseconds(static_cast<int64_t>(timeout_s * 1000.0)), ca_file);
}

std::string MapServerOptions::mapPath(const std::string& suffix) const { return "/v1/maps/" + map + suffix; }

client::HttpResponse requireOk(client::HttpResponse response, const std::string& what) {
  if (response.status >= 200 && response.status < 300) return response;
  std::string detail = response.body;
  const nlohmann::json body = nlohmann::json::parse(response.body, nullptr, false);
  if (body.is_object() && body.contains("error") && body["error"].is_object()) {
    detail = body["error"].value("code", "") + ": " + body["error"].value("message", "");
  }
  throw CommandError(what + ": HTTP " + std::to_string(response.status) + " " + detail);
}

void writeFileAtomically(const std::filesystem::path& path, const std::string& bytes) {
  std::filesystem::path partial = path;
  partial += ".partial";
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    if (!out) throw CommandError("cannot write " + partial.string());
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out.flush()) throw CommandError("writing " + partial.string() + " failed");
  }
  std::error_code ec;
  std::filesystem::rename(partial, path, ec);
  if (ec) {
    std::filesystem::remove(partial, ec);
    throw CommandError("cannot write " + path.string() + ": " + ec.message());
  }
}

std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw CommandError("cannot open " + path.string());
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (in.bad()) throw CommandError("reading " + path.string() + " failed");
  return std::move(bytes).str();
}

int runCommand(const std::string& name, const std::function<void()>& command) {
  try {
    command();
    return 0;
  } catch (const std::exception& e) {
    // CommandError, client::ClientError, bad input (std::invalid_argument), an answer that is not rmapd's.
    std::cerr << "rmap " << name << ": " << e.what() << "\n";
  }
  return 1;
}

}  // namespace rmap::cli
