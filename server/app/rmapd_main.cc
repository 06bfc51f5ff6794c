// rmapd: the mapping server. One process, one port: robots stream over
// WebSocket, browsers and programs read over HTTP (docs/API.md).
#include <CLI/CLI.hpp>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <csignal>
#include <iostream>

#include "app/config.h"
#include "app/mapping_service.h"
#include "app/protobuf_log.h"
#include "app/rmapd_service.h"
#include "app/static_files.h"
#include "net/server.h"
#include "net/tls_context.h"

namespace {

/// Waits for SIGINT/SIGTERM on the main thread (blocked everywhere else).
int waitForStopSignal() {
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  int received = 0;
  sigwait(&signals, &received);
  return received;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"rmapd — networked 3D mapping server"};
  std::string listen;
  std::string data_dir;
  std::string web_root;
  std::string config_file;
  std::string log_level;
  int io_threads = 0;
  cli.add_option("--listen", listen, "HOST:PORT to serve HTTP and WebSocket on (default 127.0.0.1:8080)");
  cli.add_option("--data-dir", data_dir, "directory of the store (default ./rmap-data)");
  cli.add_option("--web-root", web_root, "directory of the web viewer served at / (default: the build's web/)");
  cli.add_option("--config", config_file, "YAML configuration file")->check(CLI::ExistingFile);
  cli.add_option("--log-level", log_level, "trace, debug, info, warn, error")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}));
  cli.add_option("--io-threads", io_threads, "network threads")->check(CLI::PositiveNumber);
  CLI11_PARSE(cli, argc, argv);

  rmap::app::Config config;
  std::shared_ptr<boost::asio::ssl::context> tls;
  try {
    if (!config_file.empty()) rmap::app::loadConfigFile(config_file, config);
    if (!listen.empty()) rmap::app::setListenAddress(listen, config);
    if (!data_dir.empty()) config.data_dir = data_dir;
    if (!web_root.empty()) config.web_root = web_root;
    if (!log_level.empty()) config.log_level = log_level;
    if (io_threads > 0) config.io_threads = io_threads;
    rmap::app::validate(config);
    // Read now, so a missing, unreadable or mismatched file is a config error (exit 2).
    if (config.tls.enabled()) {
      try {
        tls = rmap::net::makeServerTlsContext(config.tls.certificate_file, config.tls.private_key_file);
      } catch (const std::exception& e) {
        throw std::runtime_error(std::string("tls: ") + e.what());
      }
    }
  } catch (const std::exception& e) {
    std::cerr << "rmapd: " << e.what() << "\n";
    return 2;
  }
  // Logs go to stderr: stdout carries only the machine-readable "listening on" line.
  spdlog::set_default_logger(spdlog::stderr_color_mt("rmapd"));
  spdlog::set_level(spdlog::level::from_str(config.log_level));
  rmap::app::routeProtobufLogToSpdlog();

  // Block the stop signals before any thread starts so only sigwait sees them.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
  // Under a file size limit (ulimit -f) a write past it then fails with EFBIG,
  // which the store reports like a full disk, instead of killing the server.
  std::signal(SIGXFSZ, SIG_IGN);

  try {
    // The API works without the viewer: say so once here, and GET / answers 503 with the fix.
    if (const auto missing = rmap::app::missingViewerFile(config.web_root)) {
      spdlog::warn("web viewer not installed: {} is missing; GET / answers 503 until `npm ci --prefix web` "
                   "installs it (or web_root / --web-root names an installed copy)",
                   std::filesystem::absolute(*missing).string());
    } else {
      spdlog::info("serving the web viewer from {}", std::filesystem::absolute(config.web_root).string());
    }
    rmap::app::MappingService service(config);
    rmap::app::RmapdService handlers(service);
    rmap::net::ServerOptions options;
    options.host = config.listen_host;
    options.port = config.listen_port;
    options.io_threads = config.io_threads;
    options.max_body_bytes = config.limits.max_body_bytes;
    options.tls = tls;
    rmap::net::Server server(options, handlers);
    service.setConnectionCounter([&server] { return server.connections(); });
    server.start();
    const std::string host = config.listen_host.find(':') != std::string::npos ? "[" + config.listen_host + "]"
                                                                                 : config.listen_host;
    const char* scheme = tls ? "https" : "http";
    spdlog::info("rmapd {} listening on {}://{}:{}/ (data in {}{})", rmap::app::MappingService::version(), scheme,
                 host, server.port(), config.data_dir.string(),
                 config.auth.tokens.empty() ? ", loopback clients only" : "");
    std::cout << "rmapd listening on " << scheme << "://" << host << ":" << server.port() << "/" << std::endl;
    const int signal = waitForStopSignal();
    spdlog::info("signal {}: stopping", signal);
    server.stop();
  } catch (const std::exception& e) {
    spdlog::critical("{}", e.what());
    return 1;
  }
  return 0;
}
