#pragma once
/// @file store.h
/// Durable state of rmapd in one embedded SQLite database (`<data_dir>/rmap.db`,
/// WAL journal, synchronous=FULL): the log of accepted robot messages (the
/// write-ahead log the maps are rebuilt from), maps, robots, trajectories,
/// events and map snapshots. Knows nothing of the algorithms: payloads are
/// opaque bytes.
///
/// Thread safety: every method may be called from any thread; calls are
/// serialised on one connection (writes) while reads use their own connection.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace rmap::store {

/// Any failure of the database (disk full, unwritable directory, corruption).
class StoreError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
  /// @param reason  the cause alone, without the operation and file of `what`
  StoreError(const std::string& what, std::string reason) : std::runtime_error(what), reason_(std::move(reason)) {}
  /// The cause (e.g. "database or disk is full (No space left on device)"), fit
  /// to show a client; what() when none was given.
  std::string reason() const { return reason_.empty() ? what() : reason_; }

 private:
  std::string reason_;
};

struct StoreOptions {
  /// Bytes of page cache per connection.
  int64_t cache_bytes = 64ll << 20;
  /// WAL checkpoints run in the background every this many ms (passive: they
  /// never hold up a commit) ...
  int wal_checkpoint_period_ms = 100;
  /// ... and restart the WAL once it is this many pages long (16 KiB pages).
  int wal_restart_pages = 4000;
  /// Largest size of the database file in bytes, 0 for no limit. A write that
  /// would grow the file beyond fails with StoreError ("database or disk is
  /// full") and changes nothing, as when the disk itself fills up.
  int64_t max_database_bytes = 0;
};

/// A robot message to append to the log.
struct MessageRecord {
  std::string map;
  std::string robot_id;
  uint64_t seq = 0;      ///< robot's sequence number, >= 1
  int32_t kind = 0;      ///< payload type (the RobotMessage body field number)
  int64_t received_ns = 0;
  std::string payload;   ///< serialised message, opaque here
};

/// Outcome of appending one message.
struct AppendResult {
  int64_t id = 0;          ///< log id (global order of application); the stored one for a duplicate
  bool duplicate = false;  ///< (robot_id, seq) was already in the log; nothing written
};

/// A message read back from the log.
struct StoredMessage {
  int64_t id = 0;
  MessageRecord record;
};

struct MapRecord {
  std::string name;
  double resolution_m = 0.0;
  std::string params_json;  ///< map parameters as the app wrote them
  int64_t created_ns = 0;
};

struct RobotRecord {
  std::string robot_id;
  std::string map;
  std::string sensors_json;
  int64_t first_seen_ns = 0;
  int64_t last_seen_ns = 0;
  uint64_t last_seq = 0;  ///< highest seq in the log for this robot
};

/// One pose of a trajectory (map frame).
struct TrajectoryPose {
  int64_t stamp_ns = 0;
  uint64_t seq = 0;          ///< message that produced it
  double position_m[3] = {0, 0, 0};
  double orientation_wxyz[4] = {1, 0, 0, 0};
};

struct EventRecord {
  int64_t id = 0;
  std::string map;
  std::string kind;  ///< e.g. "loop_closure"
  int64_t stamp_ns = 0;
  std::string json;  ///< event body
};

/// A loop closure as the store keeps it: the fields it is filtered and
/// deduplicated by, and a body the app wrote (poses, score).
struct LoopClosureRecord {
  int64_t id = 0;  ///< assigned by the store, increasing, never reused (a cursor for clients)
  std::string map;
  std::string source;  ///< what found it, e.g. "camera"
  std::string query_robot;
  int64_t query_stamp_ns = 0;
  std::string match_robot;
  int64_t match_stamp_ns = 0;
  int64_t detected_ns = 0;  ///< wall clock of the first detection
  std::string json;         ///< body, opaque here
  /// Wall clock when the map stopped resting on it (a later optimisation of
  /// the 2D pose graph dropped it); none while it holds.
  std::optional<int64_t> withdrawn_ns;
};

/// Which loop closures to read; empty strings match everything.
struct LoopClosureFilter {
  std::string map;
  std::string robot;   ///< either side of the closure
  std::string source;
  int64_t after_id = 0;
  size_t limit = 1000;
};

struct Snapshot {
  std::string map;
  int64_t last_message_id = 0;  ///< log messages with id <= this are in the blob
  std::string blob;             ///< map file bytes
};

class Store {
 public:
  /// Opens or creates `<data_dir>/rmap.db` (creating data_dir), checks the
  /// schema and runs an integrity check of the WAL recovery.
  /// @throws StoreError with a clear message (e.g. directory not writable)
  static std::unique_ptr<Store> open(const std::filesystem::path& data_dir, const StoreOptions& options = {});
  virtual ~Store() = default;

  /// Appends messages in one transaction; they are durable when this returns.
  /// Duplicates of (robot_id, seq) already stored, or repeated within the
  /// batch, are reported and not written. Ids increase in batch order.
  /// @throws StoreError and nothing is written (e.g. disk full)
  virtual std::vector<AppendResult> append(std::span<const MessageRecord> messages) = 0;

  /// Calls fn for every logged message of `map` (all maps when empty) with
  /// id > after_id, in id order. fn returns false to stop.
  virtual void forEachMessage(const std::string& map, int64_t after_id,
                              const std::function<bool(const StoredMessage&)>& fn) const = 0;
  virtual uint64_t messageCount() const = 0;
  /// Highest seq logged for the robot, 0 if none.
  virtual uint64_t lastSeq(const std::string& robot_id) const = 0;

  /// Creates the map if missing; returns the stored record (the first one wins).
  virtual MapRecord ensureMap(const MapRecord& map) = 0;
  virtual std::vector<MapRecord> maps() const = 0;

  /// Inserts or updates the robot (first_seen kept, last_seq never decreases).
  virtual void upsertRobot(const RobotRecord& robot) = 0;
  virtual std::vector<RobotRecord> robots() const = 0;
  virtual std::optional<RobotRecord> robot(const std::string& robot_id) const = 0;

  /// Appends poses of a robot (durable on return).
  virtual void appendTrajectory(const std::string& robot_id, std::span<const TrajectoryPose> poses) = 0;
  /// Poses with stamp_ns >= since_ns in time order, at most `limit`.
  virtual std::vector<TrajectoryPose> trajectory(const std::string& robot_id, int64_t since_ns, size_t limit) const = 0;

  /// Stores an event; returns its id (increasing).
  virtual int64_t appendEvent(const EventRecord& event) = 0;
  /// Events with id > after_id (of `map`, or all maps when empty), in id order, at most `limit`.
  virtual std::vector<EventRecord> events(const std::string& map, int64_t after_id, size_t limit) const = 0;

  /// Stores a loop closure unless one with the same map, source, query robot
  /// and stamp, and match robot and stamp is stored already (a replay of the
  /// log finds the same closures again). Durable on return.
  /// @return its id; nullopt when it was stored before (nothing written)
  virtual std::optional<int64_t> appendLoopClosure(const LoopClosureRecord& closure) = 0;
  /// Marks the stored closure with `closure`'s map, source, robots and stamps
  /// withdrawn at `withdrawn_ns` (it keeps its id and body).
  /// @return the stored closure, withdrawn; nullopt when none is stored or it
  ///         was withdrawn before (a replay of the log withdraws it again)
  virtual std::optional<LoopClosureRecord> withdrawLoopClosure(const LoopClosureRecord& closure,
                                                               int64_t withdrawn_ns) = 0;
  /// Loop closures matching `filter` with id > after_id, in id order, at most `limit`.
  virtual std::vector<LoopClosureRecord> loopClosures(const LoopClosureFilter& filter) const = 0;

  /// Replaces the map's snapshot.
  virtual void putSnapshot(const Snapshot& snapshot) = 0;
  virtual std::optional<Snapshot> snapshot(const std::string& map) const = 0;
};

}  // namespace rmap::store
