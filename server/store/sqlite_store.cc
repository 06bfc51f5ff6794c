// Store on SQLite: one writing connection serialised by a mutex, reads on a
// pool of read-only connections (WAL: readers never wait for the writer).

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cerrno>
#include <cstring>
#include <limits>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <system_error>

#include "store/checkpointer.h"
#include "store/write_gate.h"
#include "store/connection_settings.h"
#include "store/reader_pool.h"
#include "store/schema.h"
#include "store/sqlite_connection.h"
#include "store/store.h"

namespace rmap::store {
namespace {

namespace fs = std::filesystem;

constexpr std::string_view kInsertMessage =
    "INSERT INTO messages (map, robot_id, seq, kind, received_ns, payload) VALUES (?1, ?2, ?3, ?4, ?5, ?6) "
    "ON CONFLICT (robot_id, seq) DO NOTHING";
constexpr std::string_view kMessageId = "SELECT id FROM messages WHERE robot_id = ?1 AND seq = ?2";
// Both replays bind ?1 map and ?2 after_id; the one over all maps ignores ?1.
constexpr std::string_view kMessagesOfMap =
    "SELECT id, map, robot_id, seq, kind, received_ns, payload FROM messages "
    "WHERE map = ?1 AND id > ?2 ORDER BY id";
constexpr std::string_view kMessagesOfAllMaps =
    "SELECT id, map, robot_id, seq, kind, received_ns, payload FROM messages WHERE id > ?2 ORDER BY id";
constexpr std::string_view kMessageCount = "SELECT count(*) FROM messages";
constexpr std::string_view kLastSeq = "SELECT max(seq) FROM messages WHERE robot_id = ?1";

constexpr std::string_view kInsertMap =
    "INSERT INTO maps (name, resolution_m, params_json, created_ns) VALUES (?1, ?2, ?3, ?4) "
    "ON CONFLICT (name) DO NOTHING";
constexpr std::string_view kMap = "SELECT name, resolution_m, params_json, created_ns FROM maps WHERE name = ?1";
constexpr std::string_view kMaps = "SELECT name, resolution_m, params_json, created_ns FROM maps ORDER BY name";

constexpr std::string_view kUpsertRobot =
    "INSERT INTO robots (robot_id, map, sensors_json, first_seen_ns, last_seen_ns, last_seq) "
    "VALUES (?1, ?2, ?3, ?4, ?5, ?6) ON CONFLICT (robot_id) DO UPDATE SET "
    "map = excluded.map, sensors_json = excluded.sensors_json, "
    "last_seen_ns = max(last_seen_ns, excluded.last_seen_ns), last_seq = max(last_seq, excluded.last_seq)";
// last_seq also from the log: the robot row may lag behind it after a crash.
constexpr std::string_view kRobots =
    "SELECT robot_id, map, sensors_json, first_seen_ns, last_seen_ns, "
    "max(last_seq, coalesce((SELECT max(seq) FROM messages WHERE messages.robot_id = robots.robot_id), 0)) "
    "FROM robots ORDER BY robot_id";
constexpr std::string_view kRobot =
    "SELECT robot_id, map, sensors_json, first_seen_ns, last_seen_ns, "
    "max(last_seq, coalesce((SELECT max(seq) FROM messages WHERE messages.robot_id = robots.robot_id), 0)) "
    "FROM robots WHERE robot_id = ?1";

constexpr std::string_view kInsertPose =
    "INSERT OR REPLACE INTO trajectories (robot_id, stamp_ns, seq, x_m, y_m, z_m, qw, qx, qy, qz) "
    "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10)";
constexpr std::string_view kPoses =
    "SELECT stamp_ns, seq, x_m, y_m, z_m, qw, qx, qy, qz FROM trajectories "
    "WHERE robot_id = ?1 AND stamp_ns >= ?2 ORDER BY stamp_ns, seq LIMIT ?3";

constexpr std::string_view kInsertEvent = "INSERT INTO events (map, kind, stamp_ns, json) VALUES (?1, ?2, ?3, ?4)";
// Both bind ?1 map, ?2 after_id, ?3 limit; the one over all maps ignores ?1.
constexpr std::string_view kEventsOfMap =
    "SELECT id, map, kind, stamp_ns, json FROM events WHERE map = ?1 AND id > ?2 ORDER BY id LIMIT ?3";
constexpr std::string_view kEventsOfAllMaps =
    "SELECT id, map, kind, stamp_ns, json FROM events WHERE id > ?2 ORDER BY id LIMIT ?3";

constexpr std::string_view kInsertLoopClosure =
    "INSERT INTO loop_closures (map, source, query_robot, query_stamp_ns, match_robot, match_stamp_ns, detected_ns, "
    "json) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8) ON CONFLICT DO NOTHING";
#define RMAP_LOOP_CLOSURE_COLUMNS \
  "id, map, source, query_robot, query_stamp_ns, match_robot, match_stamp_ns, detected_ns, json, withdrawn_ns "
// Empty filter values match everything; the robot is on either side.
constexpr std::string_view kLoopClosures =
    "SELECT " RMAP_LOOP_CLOSURE_COLUMNS
    "FROM loop_closures WHERE (?1 = '' OR map = ?1) AND (?2 = '' OR query_robot = ?2 OR match_robot = ?2) "
    "AND (?3 = '' OR source = ?3) AND id > ?4 ORDER BY id LIMIT ?5";
constexpr std::string_view kWithdrawLoopClosure =
    "UPDATE loop_closures SET withdrawn_ns = ?7 WHERE map = ?1 AND source = ?2 AND query_robot = ?3 "
    "AND query_stamp_ns = ?4 AND match_robot = ?5 AND match_stamp_ns = ?6 AND withdrawn_ns IS NULL "
    "RETURNING " RMAP_LOOP_CLOSURE_COLUMNS;
#undef RMAP_LOOP_CLOSURE_COLUMNS

/// Binds what makes a loop closure unique (?1 map … ?6 match_stamp_ns); the strings must outlive the statement's run.
void bindLoopClosureKey(Statement& statement, const LoopClosureRecord& c) {
  statement.bindText(1, c.map);
  statement.bindText(2, c.source);
  statement.bindText(3, c.query_robot);
  statement.bind(4, c.query_stamp_ns);
  statement.bindText(5, c.match_robot);
  statement.bind(6, c.match_stamp_ns);
}

/// The loop closure in the current row of a statement that selected the columns above.
LoopClosureRecord loopClosureAt(const Statement& row) {
  return {row.int64At(0), std::string(row.textAt(1)), std::string(row.textAt(2)), std::string(row.textAt(3)),
          row.int64At(4), std::string(row.textAt(5)), row.int64At(6), row.int64At(7), std::string(row.textAt(8)),
          row.isNull(9) ? std::nullopt : std::optional<int64_t>(row.int64At(9))};
}

constexpr std::string_view kPutSnapshot =
    "INSERT INTO snapshots (map, last_message_id, blob) VALUES (?1, ?2, ?3) "
    "ON CONFLICT (map) DO UPDATE SET last_message_id = excluded.last_message_id, blob = excluded.blob";
constexpr std::string_view kSnapshot = "SELECT map, last_message_id, blob FROM snapshots WHERE map = ?1";

constexpr uint64_t kMaxSeq = std::numeric_limits<int64_t>::max();  // SQLite integers are signed 64-bit

/// Sequence numbers are stored as SQLite integers, compared and max()ed there.
void checkSeq(const std::string& robot_id, uint64_t seq, uint64_t lowest, std::string_view operation) {
  if (seq < lowest || seq > kMaxSeq)
    throw StoreError(std::string(operation) + ": seq " + std::to_string(seq) + " of robot '" + robot_id +
                     "' is outside [" + std::to_string(lowest) + ", 2^63 - 1]");
}

int64_t sqlLimit(size_t limit) {
  return static_cast<int64_t>(std::min<uint64_t>(limit, std::numeric_limits<int64_t>::max()));
}

/// Creates the data directory and checks that the database can be created in it.
void prepareDataDir(const fs::path& data_dir) {
  std::error_code error;
  fs::create_directories(data_dir, error);
  if (error) throw StoreError("cannot create data directory " + data_dir.string() + ": " + error.message());
  if (!fs::is_directory(data_dir, error))
    throw StoreError("data directory " + data_dir.string() + " is not a directory");
  if (::access(data_dir.c_str(), W_OK | X_OK) != 0)
    throw StoreError("data directory " + data_dir.string() + " is not writable: " + std::strerror(errno));
}

/// A WAL left with frames means the last process did not close the database
/// (a clean close checkpoints and deletes it): SQLite recovers from it on open.
bool walLeftBehind(const fs::path& database) {
  std::error_code error;
  const auto size = fs::file_size(fs::path(database).concat("-wal"), error);
  return !error && size > 0;
}

MapRecord readMap(const Statement& row) {
  return {std::string(row.textAt(0)), row.doubleAt(1), std::string(row.textAt(2)), row.int64At(3)};
}

RobotRecord readRobot(const Statement& row) {
  return {std::string(row.textAt(0)), std::string(row.textAt(1)), std::string(row.textAt(2)),
          row.int64At(3),           row.int64At(4),           static_cast<uint64_t>(row.int64At(5))};
}

class SqliteStore final : public Store {
 public:
  SqliteStore(const fs::path& database, const StoreOptions& options)
      : writer_(database, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE), readers_(database, options.cache_bytes) {
    if (options.wal_checkpoint_period_ms < 1 || options.wal_restart_pages < 1) {
      throw std::invalid_argument("store: wal_checkpoint_period_ms and wal_restart_pages must be >= 1");
    }
    applyWriterSettings(writer_, options);
    prepareSchema(writer_);
    Statement count(writer_, kMessageCount, "count messages");
    count.step();
    message_count_ = static_cast<uint64_t>(count.int64At(0));
    checkpointer_.emplace(database, options.cache_bytes, options.wal_restart_pages,
                          std::chrono::milliseconds(options.wal_checkpoint_period_ms), write_gate_);
  }

  /// Reads every page: after a crash, proof that WAL recovery left a sound database.
  void checkIntegrity() {
    Statement check(writer_, "PRAGMA quick_check", "check database integrity");
    if (check.step() && check.textAt(0) == "ok") return;
    throw StoreError("database " + writer_.file().string() +
                     " is damaged after an unclean shutdown: " + std::string(check.textAt(0)));
  }

  std::vector<AppendResult> append(std::span<const MessageRecord> messages) override {
    constexpr std::string_view kOperation = "append messages";
    for (const MessageRecord& message : messages) checkSeq(message.robot_id, message.seq, 1, kOperation);
    std::vector<AppendResult> results;
    results.reserve(messages.size());
    if (messages.empty()) return results;

    auto lock = write_gate_.lockWriter();
    Transaction transaction(writer_, kOperation);
    Statement insert(writer_, kInsertMessage, kOperation);
    uint64_t inserted = 0;
    for (const MessageRecord& message : messages) {
      insert.bindText(1, message.map);
      insert.bindText(2, message.robot_id);
      insert.bind(3, static_cast<int64_t>(message.seq));
      insert.bind(4, int64_t{message.kind});
      insert.bind(5, message.received_ns);
      insert.bindBlob(6, message.payload);
      insert.step();
      insert.reset();
      if (sqlite3_changes(writer_.handle()) > 0) {
        results.push_back({sqlite3_last_insert_rowid(writer_.handle()), false});
        ++inserted;
      } else {  // earlier in the log or in this batch: both are visible inside the transaction
        results.push_back({storedId(message, kOperation), true});
      }
    }
    transaction.commit();
    message_count_ += inserted;
    return results;
  }

  void forEachMessage(const std::string& map, int64_t after_id,
                      const std::function<bool(const StoredMessage&)>& fn) const override {
    const ReaderPool::Lease reader = readers_.acquire();
    Statement query(*reader, map.empty() ? kMessagesOfAllMaps : kMessagesOfMap, "replay messages");
    query.bindText(1, map);
    query.bind(2, after_id);
    StoredMessage message;  // reused: its strings keep their capacity from row to row
    MessageRecord& record = message.record;
    while (query.step()) {
      message.id = query.int64At(0);
      record.map.assign(query.textAt(1));
      record.robot_id.assign(query.textAt(2));
      record.seq = static_cast<uint64_t>(query.int64At(3));
      record.kind = static_cast<int32_t>(query.int64At(4));
      record.received_ns = query.int64At(5);
      record.payload.assign(query.blobAt(6));
      if (!fn(message)) return;
    }
  }

  uint64_t messageCount() const override { return message_count_; }

  uint64_t lastSeq(const std::string& robot_id) const override {
    const ReaderPool::Lease reader = readers_.acquire();
    Statement query(*reader, kLastSeq, "read last seq");
    query.bindText(1, robot_id);
    query.step();  // an aggregate always yields one row, NULL without messages
    return query.isNull(0) ? 0 : static_cast<uint64_t>(query.int64At(0));
  }

  MapRecord ensureMap(const MapRecord& map) override {
    constexpr std::string_view kOperation = "create map";
    auto lock = write_gate_.lockWriter();
    Statement insert(writer_, kInsertMap, kOperation);
    insert.bindText(1, map.name);
    insert.bind(2, map.resolution_m);
    insert.bindText(3, map.params_json);
    insert.bind(4, map.created_ns);
    insert.step();
    Statement query(writer_, kMap, kOperation);
    query.bindText(1, map.name);
    if (!query.step()) throw StoreError("map '" + map.name + "' missing right after its creation");
    return readMap(query);
  }

  std::vector<MapRecord> maps() const override {
    const ReaderPool::Lease reader = readers_.acquire();
    Statement query(*reader, kMaps, "list maps");
    std::vector<MapRecord> maps;
    while (query.step()) maps.push_back(readMap(query));
    return maps;
  }

  void upsertRobot(const RobotRecord& robot) override {
    constexpr std::string_view kOperation = "save robot";
    checkSeq(robot.robot_id, robot.last_seq, 0, kOperation);
    auto lock = write_gate_.lockWriter();
    Statement upsert(writer_, kUpsertRobot, kOperation);
    upsert.bindText(1, robot.robot_id);
    upsert.bindText(2, robot.map);
    upsert.bindText(3, robot.sensors_json);
    upsert.bind(4, robot.first_seen_ns);
    upsert.bind(5, robot.last_seen_ns);
    upsert.bind(6, static_cast<int64_t>(robot.last_seq));
    upsert.step();
  }

  std::vector<RobotRecord> robots() const override {
    const ReaderPool::Lease reader = readers_.acquire();
    Statement query(*reader, kRobots, "list robots");
    std::vector<RobotRecord> robots;
    while (query.step()) robots.push_back(readRobot(query));
    return robots;
  }

  std::optional<RobotRecord> robot(const std::string& robot_id) const override {
    const ReaderPool::Lease reader = readers_.acquire();
    Statement query(*reader, kRobot, "read robot");
    query.bindText(1, robot_id);
    if (!query.step()) return std::nullopt;
    return readRobot(query);
  }

  void appendTrajectory(const std::string& robot_id, std::span<const TrajectoryPose> poses) override {
    constexpr std::string_view kOperation = "append trajectory";
    if (poses.empty()) return;
    auto lock = write_gate_.lockWriter();
    Transaction transaction(writer_, kOperation);
    Statement insert(writer_, kInsertPose, kOperation);
    insert.bindText(1, robot_id);
    for (const TrajectoryPose& pose : poses) {
      insert.bind(2, pose.stamp_ns);
      insert.bind(3, static_cast<int64_t>(pose.seq));
      for (int i = 0; i < 3; ++i) insert.bind(4 + i, pose.position_m[i]);
      for (int i = 0; i < 4; ++i) insert.bind(7 + i, pose.orientation_wxyz[i]);
      insert.step();
      insert.reset();
    }
    transaction.commit();
  }

  std::vector<TrajectoryPose> trajectory(const std::string& robot_id, int64_t since_ns, size_t limit) const override {
    const ReaderPool::Lease reader = readers_.acquire();
    Statement query(*reader, kPoses, "read trajectory");
    query.bindText(1, robot_id);
    query.bind(2, since_ns);
    query.bind(3, sqlLimit(limit));
    std::vector<TrajectoryPose> poses;
    while (query.step()) {
      TrajectoryPose& pose = poses.emplace_back();
      pose.stamp_ns = query.int64At(0);
      pose.seq = static_cast<uint64_t>(query.int64At(1));
      for (int i = 0; i < 3; ++i) pose.position_m[i] = query.doubleAt(2 + i);
      for (int i = 0; i < 4; ++i) pose.orientation_wxyz[i] = query.doubleAt(5 + i);
    }
    return poses;
  }

  int64_t appendEvent(const EventRecord& event) override {
    auto lock = write_gate_.lockWriter();
    Statement insert(writer_, kInsertEvent, "append event");
    insert.bindText(1, event.map);
    insert.bindText(2, event.kind);
    insert.bind(3, event.stamp_ns);
    insert.bindText(4, event.json);
    insert.step();
    return sqlite3_last_insert_rowid(writer_.handle());
  }

  std::vector<EventRecord> events(const std::string& map, int64_t after_id, size_t limit) const override {
    const ReaderPool::Lease reader = readers_.acquire();
    Statement query(*reader, map.empty() ? kEventsOfAllMaps : kEventsOfMap, "read events");
    query.bindText(1, map);
    query.bind(2, after_id);
    query.bind(3, sqlLimit(limit));
    std::vector<EventRecord> events;
    while (query.step())
      events.push_back({query.int64At(0), std::string(query.textAt(1)), std::string(query.textAt(2)),
                        query.int64At(3), std::string(query.textAt(4))});
    return events;
  }

  std::optional<int64_t> appendLoopClosure(const LoopClosureRecord& c) override {
    auto lock = write_gate_.lockWriter();
    Statement insert(writer_, kInsertLoopClosure, "append loop closure");
    bindLoopClosureKey(insert, c);
    insert.bind(7, c.detected_ns);
    insert.bindText(8, c.json);
    insert.step();
    if (sqlite3_changes(writer_.handle()) == 0) return std::nullopt;
    return sqlite3_last_insert_rowid(writer_.handle());
  }

  std::optional<LoopClosureRecord> withdrawLoopClosure(const LoopClosureRecord& c, int64_t withdrawn_ns) override {
    auto lock = write_gate_.lockWriter();
    Statement update(writer_, kWithdrawLoopClosure, "withdraw loop closure");
    bindLoopClosureKey(update, c);
    update.bind(7, withdrawn_ns);
    if (!update.step()) return std::nullopt;
    LoopClosureRecord withdrawn = loopClosureAt(update);
    while (update.step()) {}  // RETURNING: the update completes when the statement is run to its end
    return withdrawn;
  }

  std::vector<LoopClosureRecord> loopClosures(const LoopClosureFilter& filter) const override {
    const ReaderPool::Lease reader = readers_.acquire();
    Statement query(*reader, kLoopClosures, "read loop closures");
    query.bindText(1, filter.map);
    query.bindText(2, filter.robot);
    query.bindText(3, filter.source);
    query.bind(4, filter.after_id);
    query.bind(5, sqlLimit(filter.limit));
    std::vector<LoopClosureRecord> out;
    while (query.step()) out.push_back(loopClosureAt(query));
    return out;
  }

  void putSnapshot(const Snapshot& snapshot) override {
    auto lock = write_gate_.lockWriter();
    Statement put(writer_, kPutSnapshot, "save snapshot");
    put.bindText(1, snapshot.map);
    put.bind(2, snapshot.last_message_id);
    put.bindBlob(3, snapshot.blob);
    put.step();
  }

  std::optional<Snapshot> snapshot(const std::string& map) const override {
    const ReaderPool::Lease reader = readers_.acquire();
    Statement query(*reader, kSnapshot, "read snapshot");
    query.bindText(1, map);
    if (!query.step()) return std::nullopt;
    return Snapshot{std::string(query.textAt(0)), query.int64At(1), std::string(query.blobAt(2))};
  }

 private:
  /// Id of the logged message with the same (robot_id, seq); the caller holds the write lock.
  int64_t storedId(const MessageRecord& message, std::string_view operation) {
    Statement query(writer_, kMessageId, operation);
    query.bindText(1, message.robot_id);
    query.bind(2, static_cast<int64_t>(message.seq));
    if (!query.step()) throw StoreError("message " + message.robot_id + "#" + std::to_string(message.seq) +
                                        " was refused as a duplicate but is not in the log");
    return query.int64At(0);
  }

  WriteGate write_gate_;
  Connection writer_;
  ReaderPool readers_;
  /// Declared last: its thread stops before the connections close.
  std::optional<Checkpointer> checkpointer_;
  /// Rows of the messages table, kept here because count(*) scans the table.
  std::atomic<uint64_t> message_count_ = 0;
};

}  // namespace

std::unique_ptr<Store> Store::open(const fs::path& data_dir, const StoreOptions& options) {
  prepareDataDir(data_dir);
  const fs::path database = data_dir / "rmap.db";
  const bool recovering = walLeftBehind(database);
  auto store = std::make_unique<SqliteStore>(database, options);
  // Only after a crash: quick_check reads the whole file, too slow for every start.
  if (recovering) store->checkIntegrity();
  return store;
}

}  // namespace rmap::store
