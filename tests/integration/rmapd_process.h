#pragma once
/// @file rmapd_process.h
/// Runs a real rmapd for end-to-end tests: a child process on 127.0.0.1
/// port 0 whose bound port is read from its first line of stdout.

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

namespace rmap::testing {

/// The rmapd binary of this build.
const char* rmapdPath();
/// The rmap CLI binary of this build.
const char* rmapCliPath();

/// Writes `bytes` to `path` (creating its folders), replacing what was there.
/// @throws std::runtime_error when it cannot
void writeFile(const std::filesystem::path& path, const std::string& bytes);

/// A fresh directory under the system temp dir, removed by the destructor.
class TempDir {
 public:
  explicit TempDir(const std::string& prefix);
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

class RmapdProcess {
 public:
  /// Starts rmapd with `--listen 127.0.0.1:0 --data-dir data_dir` plus the
  /// config file (written from `config_yaml` beside the data dir when not
  /// empty) and `extra_args` (a `--listen` there replaces the default one),
  /// and waits until it listens.
  /// @throws std::runtime_error with rmapd's log when it does not come up in time
  RmapdProcess(const std::filesystem::path& data_dir, const std::string& config_yaml = {},
               std::chrono::seconds startup_timeout = std::chrono::seconds(60),
               const std::vector<std::string>& extra_args = {});
  /// Terminates it (SIGTERM, then SIGKILL after a grace period).
  ~RmapdProcess();
  RmapdProcess(const RmapdProcess&) = delete;
  RmapdProcess& operator=(const RmapdProcess&) = delete;

  uint16_t port() const { return port_; }
  /// The process id while it runs (e.g. to set its resource limits), -1 after it ended.
  pid_t pid() const { return pid_; }
  std::string httpUrl() const { return "http://127.0.0.1:" + std::to_string(port_); }
  std::string wsUrl() const { return "ws://127.0.0.1:" + std::to_string(port_); }
  /// SIGKILL and reap: a crash.
  void kill9();
  /// SIGTERM and wait; returns the exit status (or -1 when it had to be killed).
  int terminate(std::chrono::seconds grace = std::chrono::seconds(30));
  bool running();
  /// What rmapd wrote to stderr so far.
  std::string log() const;

 private:
  pid_t pid_ = -1;
  uint16_t port_ = 0;
  std::filesystem::path log_path_;
};

}  // namespace rmap::testing
