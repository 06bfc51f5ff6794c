// A disk that fills up during ingest, and data directories rmapd cannot use.
//
// The full disk is rmapd's file size limit (RLIMIT_FSIZE) lowered while it
// runs: writes past it fail with EFBIG (rmapd ignores SIGXFSZ) as they fail
// with ENOSPC on a full disk, with no root and no mount. rmapd must then stop
// acknowledging (every message gets Error `unavailable` naming the cause),
// log why, keep serving reads and keep refused messages out of the map; once
// the space is back, live or after kill -9 and a restart, the refused
// messages resent with their seq are stored, nothing acknowledged is lost
// and the database passes SQLite's integrity check.
#include <sys/resource.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <numeric>
#include <optional>
#include <thread>

#include "api_helpers.h"
#include "client/robot_client.h"
#include "column_clouds.h"
#include "rmapd_process.h"
#include "store_copy.h"

namespace rmap::testing {
namespace {

namespace fs = std::filesystem;

constexpr const char* kFullMap = "full";
constexpr const char* kRobot = "full-bot";
// Snapshots every 0.3 s: one taken after the space is back must not cover poses a failed write lost.
constexpr const char* kStorageConfig = "snapshot_interval_s: 0.3\nmaps:\n  fusion_tolerance_log_odds: 0\n";

/// Sets the soft file size limit of a running process (the hard one stays).
void setFileSizeLimit(pid_t pid, rlim_t bytes) {
  rlimit limit{};
  ASSERT_EQ(prlimit(pid, RLIMIT_FSIZE, nullptr, &limit), 0) << std::strerror(errno);
  limit.rlim_cur = bytes;
  ASSERT_EQ(prlimit(pid, RLIMIT_FSIZE, &limit, nullptr), 0) << std::strerror(errno);
}

/// A robot sending one message at a time and waiting for its answer.
class OneByOne {
 public:
  explicit OneByOne(const std::string& url) {
    client::RobotClientOptions options;
    options.server_url = url;
    options.hello.set_robot_id(kRobot);
    options.hello.set_map(kFullMap);
    options.timeout = std::chrono::seconds(10);
    robot_ = std::make_unique<client::RobotClient>(options);
    robot_->onAck([this](const v1::Ack& ack, std::chrono::nanoseconds) {
      std::lock_guard lock(mutex_);
      acks_[ack.seq()] = ack;
    });
    robot_->onError([this](const v1::Error& e) {
      std::lock_guard lock(mutex_);
      errors_[e.seq()] = e;
    });
    last_durable_ = robot_->connect().last_durable_seq();
  }

  uint64_t lastDurable() const { return last_durable_; }

  /// Sends cloud `seq` (a new one when seq is past every seq sent) and waits.
  /// @return its Ack, or nullopt when it drew an Error (in lastError())
  std::optional<v1::Ack> send(uint64_t seq) {
    {
      std::lock_guard lock(mutex_);
      acks_.erase(seq);
      errors_.erase(seq);
    }
    v1::RobotMessage m = columnCloud(seq - 1, static_cast<int64_t>(seq));
    m.set_seq(seq);
    robot_->resend(m);
    EXPECT_TRUE(robot_->waitAllAcked(std::chrono::seconds(10))) << "seq " << seq << " unanswered";
    std::lock_guard lock(mutex_);
    if (const auto it = acks_.find(seq); it != acks_.end()) return it->second;
    const auto it = errors_.find(seq);
    EXPECT_NE(it, errors_.end()) << "seq " << seq << ": neither Ack nor Error";
    if (it != errors_.end()) last_error_ = it->second;
    return std::nullopt;
  }

  const v1::Error& lastError() const { return last_error_; }

 private:
  std::unique_ptr<client::RobotClient> robot_;
  uint64_t last_durable_ = 0;
  std::mutex mutex_;
  std::map<uint64_t, v1::Ack> acks_;
  std::map<uint64_t, v1::Error> errors_;
  v1::Error last_error_;
};

/// Clouds 1..acked are in the map once, the `refused` ones not at all.
void expectInMap(client::HttpClient& http, uint64_t acked, const std::vector<uint64_t>& refused) {
  std::vector<Eigen::Vector3d> probes;
  for (uint64_t seq = 1; seq <= acked; ++seq) {
    for (const Eigen::Vector3d& p : columnEndpoints(seq - 1)) probes.push_back(p);
  }
  const size_t in = probes.size();
  for (const uint64_t seq : refused) {
    for (const Eigen::Vector3d& p : columnEndpoints(seq - 1)) probes.push_back(p);
  }
  const v1::OccupancyBatchResponse served = batchQuery(http, kFullMap, probes);
  ASSERT_EQ(static_cast<size_t>(served.states_size()), probes.size());
  for (size_t i = 0; i < probes.size(); ++i) {
    const int i32 = static_cast<int>(i);
    if (i < in) {
      ASSERT_EQ(served.states(i32), v1::OCCUPIED) << probes[i].transpose();
      ASSERT_NEAR(served.probabilities(i32), oneHitProbability(), 1e-6) << probes[i].transpose();
    } else {
      ASSERT_EQ(served.states(i32), v1::UNKNOWN) << "a refused cloud reached the map at " << probes[i].transpose();
    }
  }
}

/// Waits (poses are written every 0.5 s) until the trajectory holds a pose for each seq 1..acked.
void expectTrajectory(client::HttpClient& http, uint64_t acked) {
  std::vector<uint64_t> seqs;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (std::chrono::steady_clock::now() < deadline) {
    seqs.clear();
    const nlohmann::json trajectory = getJson(http, std::string("/v1/robots/") + kRobot + "/trajectory?limit=100000");
    for (const nlohmann::json& pose : trajectory["poses"]) seqs.push_back(pose["seq"].get<uint64_t>());
    std::sort(seqs.begin(), seqs.end());
    if (seqs.size() >= acked) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::vector<uint64_t> expected(acked);
  std::iota(expected.begin(), expected.end(), 1);
  EXPECT_EQ(seqs, expected) << "trajectory poses missing";
}

/// Fills the "disk": sends new clouds after `next_seq` until one is refused,
/// then 4 more, which must be refused too. Returns the refused seqs; `next_seq`
/// moves past everything sent and `acked` counts the clouds acknowledged.
std::vector<uint64_t> fillUntilRefused(OneByOne& robot, uint64_t& next_seq, uint64_t& acked) {
  std::vector<uint64_t> refused;
  for (int n = 0; n < 400 && refused.empty(); ++n, ++next_seq) {
    if (robot.send(next_seq)) {
      EXPECT_EQ(next_seq, acked + 1) << "a cloud was acknowledged after an earlier one was refused";
      ++acked;
    } else {
      refused.push_back(next_seq);
    }
  }
  EXPECT_FALSE(refused.empty()) << "400 clouds past the file size limit were all acknowledged";
  for (int n = 0; n < 4 && !refused.empty(); ++n, ++next_seq) {
    EXPECT_FALSE(robot.send(next_seq)) << "seq " << next_seq << " acknowledged on a full disk";
    refused.push_back(next_seq);
  }
  return refused;
}

TEST(StorageFaults, FullDiskStopsAcknowledgementsKeepsReadsAndLosesNothing) {
  TempDir dir("rmap-full");
  const fs::path data = dir.path() / "data";
  auto rmapd = std::make_unique<RmapdProcess>(data, kStorageConfig);
  auto robot = std::make_unique<OneByOne>(rmapd->wsUrl());
  uint64_t next_seq = 1, acked = 0;
  for (; next_seq <= 20; ++next_seq, ++acked) ASSERT_TRUE(robot->send(next_seq)) << "seq " << next_seq;

  // The disk fills: no file of rmapd may grow past its log's size plus 64 KiB.
  const auto limit = [&] { return static_cast<rlim_t>(fs::file_size(dir.path() / "data-rmapd.log") + (64 << 10)); };
  setFileSizeLimit(rmapd->pid(), limit());
  std::vector<uint64_t> refused = fillUntilRefused(*robot, next_seq, acked);
  ASSERT_FALSE(refused.empty());
  const v1::Error& error = robot->lastError();
  EXPECT_EQ(error.code(), "unavailable");
  EXPECT_FALSE(error.fatal());
  EXPECT_NE(error.message().find("could not be stored (disk I/O error"), std::string::npos)
      << error.message();
  EXPECT_EQ(error.message().find(data.string()), std::string::npos) << "the robot is told the server's paths";
  EXPECT_NE(rmapd->log().find("not stored: append messages failed on " + (data / "rmap.db").string()),
            std::string::npos)
      << rmapd->log();

  // Reads go on while it stays full (past a trajectory flush, a snapshot and checkpoints that
  // fail); the refused clouds are not in the map.
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  EXPECT_FALSE(robot->send(next_seq)) << "acknowledged on a full disk";
  refused.push_back(next_seq++);
  {
    // A new robot cannot even be registered: its Hello is refused, naming the cause.
    client::RobotClientOptions options;
    options.server_url = rmapd->wsUrl();
    options.hello.set_robot_id("late-bot");
    options.hello.set_map(kFullMap);
    client::RobotClient late(options);
    try {
      late.connect();
      ADD_FAILURE() << "a Hello was welcomed on a full disk";
    } catch (const client::ClientError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("unavailable: cannot open the session: disk I/O error"), std::string::npos) << what;
      EXPECT_EQ(what.find(data.string()), std::string::npos) << what;
    }
  }
  client::HttpClient http(rmapd->httpUrl());
  EXPECT_EQ(getJson(http, "/healthz")["status"], "ok");
  expectInMap(http, acked, refused);
  EXPECT_GE(metricValue(http.get("/metrics").body, "rmap_store_failures_total"), static_cast<double>(refused.size()));

  const size_t refused_first = refused.size();
  // Space comes back while rmapd runs: the refused clouds resent with their seq are stored.
  setFileSizeLimit(rmapd->pid(), RLIM_INFINITY);
  for (const uint64_t seq : refused) {
    const std::optional<v1::Ack> ack = robot->send(seq);
    ASSERT_TRUE(ack) << "seq " << seq << " refused again: " << robot->lastError().message();
    EXPECT_FALSE(ack->duplicate()) << "a refused message had been stored";
  }
  acked += refused.size();
  expectInMap(http, acked, {});
  expectTrajectory(http, acked);

  // Full again, then kill -9 while full and a restart with the space back.
  setFileSizeLimit(rmapd->pid(), limit());
  refused = fillUntilRefused(*robot, next_seq, acked);
  ASSERT_FALSE(refused.empty());
  robot.reset();
  rmapd->kill9();
  const StoreContents copy = readStoreCopy(data, dir.path() / "copy");
  EXPECT_EQ(copy.integrity, "ok");
  std::vector<uint64_t> expected(acked);
  std::iota(expected.begin(), expected.end(), 1);
  EXPECT_EQ(copy.seqs.at(kRobot), expected) << "the log is not exactly the acknowledged clouds";

  rmapd = std::make_unique<RmapdProcess>(data, kStorageConfig);
  robot = std::make_unique<OneByOne>(rmapd->wsUrl());
  EXPECT_EQ(robot->lastDurable(), acked);
  client::HttpClient after(rmapd->httpUrl());
  expectInMap(after, acked, refused);
  for (const uint64_t seq : refused) {
    const std::optional<v1::Ack> ack = robot->send(seq);
    ASSERT_TRUE(ack) << "seq " << seq << ": " << robot->lastError().message();
    EXPECT_FALSE(ack->duplicate());
  }
  expectInMap(after, acked + refused.size(), {});
  expectTrajectory(after, acked + refused.size());
  std::printf("[ full disk ] %llu clouds acknowledged, %zu + %zu refused while full and stored once resent\n",
              static_cast<unsigned long long>(acked + refused.size()), refused_first, refused.size());
}

TEST(StorageFaults, DataDirectoryThatIsAFileIsRefusedAtStart) {
  TempDir dir("rmap-nodir");
  const fs::path data = dir.path() / "data";
  std::ofstream(data) << "not a directory";
  try {
    RmapdProcess rmapd(data);
    ADD_FAILURE() << "rmapd started on a file as its data directory";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("data directory " + data.string()), std::string::npos) << what;
  }
  std::ifstream in(data);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "not a directory");
}

TEST(StorageFaults, ReadOnlyDataDirectoryIsRefusedAtStart) {
  if (geteuid() == 0) GTEST_SKIP() << "root writes into read-only directories; run as a normal user";
  TempDir dir("rmap-readonly");
  const fs::path data = dir.path() / "data";
  fs::create_directories(data);
  fs::permissions(data, fs::perms::owner_read | fs::perms::owner_exec);
  try {
    RmapdProcess rmapd(data);
    ADD_FAILURE() << "rmapd started on a read-only data directory";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("data directory " + data.string() + " is not writable"), std::string::npos)
        << e.what();
  }
  fs::permissions(data, fs::perms::owner_all);
  EXPECT_TRUE(fs::is_empty(data));
}

}  // namespace
}  // namespace rmap::testing
