#include "store/schema.h"

#include <iterator>
#include <string>

namespace rmap::store {
namespace {

// Integers that are uint64_t in the API (seq, last_seq) are stored as SQLite's
// signed 64-bit INTEGER; the store keeps them below 2^63 so they sort right.
// Version 1: the tables every database has.
constexpr const char* kVersion1Tables = R"sql(
CREATE TABLE maps (
  name         TEXT PRIMARY KEY,
  resolution_m REAL NOT NULL,
  params_json  TEXT NOT NULL,
  created_ns   INTEGER NOT NULL
);

-- The log the maps are rebuilt from; id is the global order of application.
-- Not AUTOINCREMENT: nothing is ever deleted, so max(id) + 1 already increases.
CREATE TABLE messages (
  id          INTEGER PRIMARY KEY,
  map         TEXT NOT NULL,
  robot_id    TEXT NOT NULL,
  seq         INTEGER NOT NULL,
  kind        INTEGER NOT NULL,
  received_ns INTEGER NOT NULL,
  payload     BLOB NOT NULL,
  UNIQUE (robot_id, seq)  -- detects duplicates; also answers max(seq) per robot
);
CREATE INDEX messages_by_map ON messages (map, id);  -- replay of one map

CREATE TABLE robots (
  robot_id      TEXT PRIMARY KEY,
  map           TEXT NOT NULL,
  sensors_json  TEXT NOT NULL,
  first_seen_ns INTEGER NOT NULL,
  last_seen_ns  INTEGER NOT NULL,
  last_seq      INTEGER NOT NULL
);

-- Clustered by robot and time, the order of every query; a pose re-appended
-- (e.g. while replaying the log after a crash) replaces its earlier copy.
CREATE TABLE trajectories (
  robot_id TEXT NOT NULL,
  stamp_ns INTEGER NOT NULL,
  seq      INTEGER NOT NULL,
  x_m REAL NOT NULL, y_m REAL NOT NULL, z_m REAL NOT NULL,
  qw REAL NOT NULL, qx REAL NOT NULL, qy REAL NOT NULL, qz REAL NOT NULL,
  PRIMARY KEY (robot_id, stamp_ns, seq)
) WITHOUT ROWID;

-- AUTOINCREMENT: event ids are handed to clients as cursors and must never be reused.
CREATE TABLE events (
  id       INTEGER PRIMARY KEY AUTOINCREMENT,
  map      TEXT NOT NULL,
  kind     TEXT NOT NULL,
  stamp_ns INTEGER NOT NULL,
  json     TEXT NOT NULL
);
CREATE INDEX events_by_map ON events (map, id);

CREATE TABLE snapshots (
  map             TEXT PRIMARY KEY,
  last_message_id INTEGER NOT NULL,
  blob            BLOB NOT NULL
);
)sql";

// Version 2: loop closures. The unique key is what makes a replay of the log, which finds
// the same closures again, store nothing twice.
constexpr const char* kVersion2Tables = R"sql(
CREATE TABLE loop_closures (
  id             INTEGER PRIMARY KEY AUTOINCREMENT,  -- a cursor for clients: never reused
  map            TEXT NOT NULL,
  source         TEXT NOT NULL,
  query_robot    TEXT NOT NULL,
  query_stamp_ns INTEGER NOT NULL,
  match_robot    TEXT NOT NULL,
  match_stamp_ns INTEGER NOT NULL,
  detected_ns    INTEGER NOT NULL,
  json           TEXT NOT NULL,
  UNIQUE (map, source, query_robot, query_stamp_ns, match_robot, match_stamp_ns)
);
CREATE INDEX loop_closures_by_map ON loop_closures (map, id);
)sql";

// Version 3: a loop closure the 2D pose graph dropped after reporting it is kept, marked withdrawn.
constexpr const char* kVersion3Columns = "ALTER TABLE loop_closures ADD COLUMN withdrawn_ns INTEGER;";

/// Tables and columns added by each version, in order: a database at version v gets those after v.
constexpr const char* kMigrations[] = {kVersion1Tables, kVersion2Tables, kVersion3Columns};
static_assert(std::size(kMigrations) == kSchemaVersion);

int userVersion(Connection& connection) {
  Statement query(connection, "PRAGMA user_version", "read schema version");
  query.step();
  return static_cast<int>(query.int64At(0));
}

}  // namespace

void prepareSchema(Connection& writer) {
  constexpr std::string_view kOperation = "create schema";
  Transaction transaction(writer, kOperation);
  const int version = userVersion(writer);  // read inside the write lock: another process may be creating it
  if (version > kSchemaVersion)
    throw StoreError("database " + writer.file().string() + " has schema version " + std::to_string(version) +
                     ", newer than version " + std::to_string(kSchemaVersion) +
                     " supported by this rmapd; run a newer rmapd or another data directory");
  if (version == kSchemaVersion) return;  // the transaction only read: its rollback changes nothing
  for (int v = version; v < kSchemaVersion; ++v) writer.exec(kMigrations[v], kOperation);
  writer.exec("PRAGMA user_version = " + std::to_string(kSchemaVersion), kOperation);
  transaction.commit();
}

}  // namespace rmap::store
