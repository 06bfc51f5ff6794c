#include "store/store.h"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <chrono>
#include <fstream>
#include <future>
#include <thread>

#include "store/schema.h"
#include "temp_dir.h"

namespace rmap::store {
namespace {

using namespace std::chrono_literals;

MessageRecord message(const std::string& map, const std::string& robot, uint64_t seq, std::string payload) {
  return {map, robot, seq, static_cast<int32_t>(seq % 7), static_cast<int64_t>(seq % 1'000'000) * 1'000'000 + 17,
          std::move(payload)};
}

/// Bytes that survive only a binary-safe round trip: NULs, high bytes, no UTF-8.
std::string binaryPayload(size_t size, uint8_t salt) {
  std::string bytes(size, '\0');
  for (size_t i = 0; i < size; ++i) bytes[i] = static_cast<char>((i * 131 + salt) % 256);
  return bytes;
}

std::vector<StoredMessage> allMessages(const Store& store, const std::string& map = "", int64_t after_id = 0) {
  std::vector<StoredMessage> messages;
  store.forEachMessage(map, after_id, [&](const StoredMessage& m) {
    messages.push_back(m);
    return true;
  });
  return messages;
}

std::vector<int64_t> idsOf(const std::vector<StoredMessage>& messages) {
  std::vector<int64_t> ids;
  for (const StoredMessage& m : messages) ids.push_back(m.id);
  return ids;
}

void expectSameRecord(const MessageRecord& actual, const MessageRecord& expected) {
  EXPECT_EQ(actual.map, expected.map);
  EXPECT_EQ(actual.robot_id, expected.robot_id);
  EXPECT_EQ(actual.seq, expected.seq);
  EXPECT_EQ(actual.kind, expected.kind);
  EXPECT_EQ(actual.received_ns, expected.received_ns);
  EXPECT_EQ(actual.payload, expected.payload);
}

/// Runs `sql` on its own connection (as another process would) and returns
/// the first column of the first row.
std::string queryDirectly(const std::filesystem::path& database, const std::string& sql) {
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open(database.c_str(), &db), SQLITE_OK);
  sqlite3_stmt* statement = nullptr;
  std::string value;
  if (sqlite3_prepare_v2(db, sql.c_str(), -1, &statement, nullptr) == SQLITE_OK &&
      sqlite3_step(statement) == SQLITE_ROW && sqlite3_column_text(statement, 0))
    value = reinterpret_cast<const char*>(sqlite3_column_text(statement, 0));
  sqlite3_finalize(statement);
  sqlite3_close(db);
  return value;
}

template <class Fn>
std::string storeErrorOf(Fn&& fn) {
  try {
    fn();
  } catch (const StoreError& error) {
    return error.what();
  }
  ADD_FAILURE() << "no StoreError thrown";
  return {};
}

TEST(Store, OpenCreatesDataDirAndWalDatabaseWithSchemaVersion) {
  TempDir tmp;
  const auto data_dir = tmp.path() / "nested" / "data";
  { const auto store = Store::open(data_dir); }
  ASSERT_TRUE(std::filesystem::exists(data_dir / "rmap.db"));
  EXPECT_EQ(queryDirectly(data_dir / "rmap.db", "PRAGMA journal_mode"), "wal");
  EXPECT_EQ(queryDirectly(data_dir / "rmap.db", "PRAGMA user_version"), std::to_string(kSchemaVersion));
}

TEST(Store, MessagesRoundTripWithIncreasingIds) {
  TempDir tmp;
  const auto store = Store::open(tmp.path());
  const std::vector<MessageRecord> batch = {message("hall", "r1", 1, binaryPayload(100'000, 1)),
                                            message("yard", "r2", 1, ""),
                                            message("hall", "r1", 2, binaryPayload(3, 2))};
  const auto results = store->append(batch);
  ASSERT_EQ(results.size(), 3u);
  for (const AppendResult& r : results) EXPECT_FALSE(r.duplicate);
  EXPECT_LT(results[0].id, results[1].id);
  EXPECT_LT(results[1].id, results[2].id);
  const auto later = store->append(std::vector{message("hall", "r3", 9, "x")});
  EXPECT_GT(later.at(0).id, results[2].id);

  const auto stored = allMessages(*store);
  ASSERT_EQ(stored.size(), 4u);
  for (size_t i = 0; i < batch.size(); ++i) {
    EXPECT_EQ(stored[i].id, results[i].id);
    expectSameRecord(stored[i].record, batch[i]);
  }
  EXPECT_EQ(store->messageCount(), 4u);
  EXPECT_TRUE(store->append({}).empty());
}

TEST(Store, DuplicateOfLoggedMessageReportsStoredIdAndWritesNothing) {
  TempDir tmp;
  const auto store = Store::open(tmp.path());
  const auto first = store->append(std::vector{message("m", "r1", 1, "original"), message("m", "r1", 2, "b")});
  const auto second = store->append(std::vector{message("m", "r1", 3, "c"), message("m", "r1", 1, "resent")});
  EXPECT_FALSE(second[0].duplicate);
  EXPECT_GT(second[0].id, first[1].id);
  EXPECT_TRUE(second[1].duplicate);
  EXPECT_EQ(second[1].id, first[0].id);

  const auto stored = allMessages(*store);
  ASSERT_EQ(stored.size(), 3u);
  EXPECT_EQ(stored[0].record.payload, "original");
  EXPECT_EQ(store->messageCount(), 3u);
  // The same seq from another robot is no duplicate.
  EXPECT_FALSE(store->append(std::vector{message("m", "r2", 1, "other")})[0].duplicate);
}

TEST(Store, DuplicateWithinOneBatchIsWrittenOnce) {
  TempDir tmp;
  const auto store = Store::open(tmp.path());
  const auto results = store->append(
      std::vector{message("m", "r", 5, "first"), message("m", "r", 5, "second"), message("m", "r", 6, "next")});
  EXPECT_FALSE(results[0].duplicate);
  EXPECT_TRUE(results[1].duplicate);
  EXPECT_EQ(results[1].id, results[0].id);
  EXPECT_FALSE(results[2].duplicate);
  EXPECT_GT(results[2].id, results[0].id);
  const auto stored = allMessages(*store);
  ASSERT_EQ(stored.size(), 2u);
  EXPECT_EQ(stored[0].record.payload, "first");
  EXPECT_EQ(stored[1].record.payload, "next");
}

TEST(Store, ForEachMessageFiltersByMapAndAfterId) {
  TempDir tmp;
  const auto store = Store::open(tmp.path());
  std::vector<MessageRecord> batch;
  for (uint64_t seq = 1; seq <= 10; ++seq) batch.push_back(message(seq % 3 == 0 ? "b" : "a", "r", seq, "p"));
  const auto results = store->append(batch);
  std::vector<int64_t> of_a, of_all_after_fifth;
  for (size_t i = 0; i < batch.size(); ++i) {
    if (batch[i].map == "a") of_a.push_back(results[i].id);
    if (i >= 5) of_all_after_fifth.push_back(results[i].id);
  }
  EXPECT_EQ(idsOf(allMessages(*store, "a")), of_a);
  EXPECT_EQ(idsOf(allMessages(*store, "a", of_a[2])), std::vector(of_a.begin() + 3, of_a.end()));
  EXPECT_EQ(idsOf(allMessages(*store, "", results[4].id)), of_all_after_fifth);
  for (const StoredMessage& m : allMessages(*store, "b")) EXPECT_EQ(m.record.map, "b");
  EXPECT_EQ(allMessages(*store, "b").size(), 3u);
  EXPECT_TRUE(allMessages(*store, "nowhere").empty());
  EXPECT_TRUE(allMessages(*store, "", results.back().id).empty());
}

TEST(Store, ForEachMessageStopsWhenTheCallbackSaysSo) {
  TempDir tmp;
  const auto store = Store::open(tmp.path());
  std::vector<MessageRecord> batch;
  for (uint64_t seq = 1; seq <= 10; ++seq) batch.push_back(message("m", "r", seq, "p"));
  store->append(batch);
  std::vector<uint64_t> seen;
  store->forEachMessage("m", 0, [&](const StoredMessage& m) {
    seen.push_back(m.record.seq);
    return seen.size() < 3;
  });
  EXPECT_EQ(seen, (std::vector<uint64_t>{1, 2, 3}));
}

TEST(Store, ReplayCallbackMayQueryAndAppendAndSeesItsSnapshotOnly) {
  TempDir tmp;
  const auto store = Store::open(tmp.path());
  store->append(std::vector{message("m", "r", 1, "a"), message("m", "r", 2, "b")});
  size_t seen = 0;
  store->forEachMessage("", 0, [&](const StoredMessage& m) {
    ++seen;
    EXPECT_EQ(store->lastSeq("r"), 1 + m.record.seq);  // each callback appended one more
    store->append(std::vector{message("m", "r", 2 + m.record.seq, "appended during replay")});
    EXPECT_FALSE(allMessages(*store).empty());  // a nested replay
    return true;
  });
  EXPECT_EQ(seen, 2u);  // the replay reads the log as of its start
  EXPECT_EQ(store->messageCount(), 4u);
}

TEST(Store, ReadsDoNotWaitForAWriteInProgress) {
  TempDir tmp;
  const auto store = Store::open(tmp.path());
  store->append(std::vector{message("m", "r", 1, "a")});
  // Another process holds the write lock: the store's append waits for it,
  // holding the store's write mutex meanwhile.
  sqlite3* other = nullptr;
  ASSERT_EQ(sqlite3_open((tmp.path() / "rmap.db").c_str(), &other), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(other, "BEGIN IMMEDIATE", nullptr, nullptr, nullptr), SQLITE_OK);
  auto append = std::async(std::launch::async, [&] { return store->append(std::vector{message("m", "r", 2, "b")}); });
  std::this_thread::sleep_for(100ms);  // lets the append reach the lock

  EXPECT_EQ(store->lastSeq("r"), 1u);
  EXPECT_EQ(allMessages(*store).size(), 1u);
  EXPECT_TRUE(store->maps().empty());
  EXPECT_EQ(append.wait_for(0s), std::future_status::timeout) << "reads waited for the write";

  ASSERT_EQ(sqlite3_exec(other, "COMMIT", nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(other);
  EXPECT_FALSE(append.get().at(0).duplicate);
  EXPECT_EQ(store->lastSeq("r"), 2u);
}

TEST(Store, LastSeqComesFromTheLogAndSurvivesReopen) {
  TempDir tmp;
  {
    const auto store = Store::open(tmp.path());
    EXPECT_EQ(store->lastSeq("r1"), 0u);
    store->append(std::vector{message("m", "r1", 1, ""), message("m", "r1", 7, ""), message("m", "r2", 3, "")});
    store->append(std::vector{message("m", "r1", 2, "")});  // late, below the highest
    store->upsertRobot({"r1", "m", "{}", 10, 20, 2});        // behind the log, as after a crash
    EXPECT_EQ(store->lastSeq("r1"), 7u);
  }
  const auto store = Store::open(tmp.path());
  EXPECT_EQ(store->lastSeq("r1"), 7u);
  EXPECT_EQ(store->lastSeq("r2"), 3u);
  EXPECT_EQ(store->lastSeq("r3"), 0u);
  ASSERT_TRUE(store->robot("r1"));
  EXPECT_EQ(store->robot("r1")->last_seq, 7u);
}

TEST(Store, EnsureMapKeepsTheFirstRecord) {
  TempDir tmp;
  const auto store = Store::open(tmp.path());
  const MapRecord hall{"hall", 0.05, R"({"max_range_m":30})", 111};
  const MapRecord created = store->ensureMap(hall);
  EXPECT_EQ(created.name, "hall");
  EXPECT_EQ(created.resolution_m, 0.05);
  EXPECT_EQ(created.params_json, hall.params_json);
  EXPECT_EQ(created.created_ns, 111);
  const MapRecord again = store->ensureMap({"hall", 0.2, "{}", 222});
  EXPECT_EQ(again.resolution_m, 0.05);
  EXPECT_EQ(again.created_ns, 111);
  store->ensureMap({"atrium", 0.1, "{}", 333});
  const auto maps = store->maps();
  ASSERT_EQ(maps.size(), 2u);
  EXPECT_EQ(maps[0].name, "atrium");
  EXPECT_EQ(maps[1].name, "hall");
  EXPECT_EQ(maps[1].params_json, hall.params_json);
}

TEST(Store, UpsertRobotKeepsFirstSeenAndNeverLowersLastSeq) {
  TempDir tmp;
  const auto store = Store::open(tmp.path());
  EXPECT_FALSE(store->robot("r1"));
  store->upsertRobot({"r1", "hall", R"({"lidar":1})", 100, 150, 5});
  store->upsertRobot({"r1", "yard", R"({"lidar":2})", 900, 950, 3});
  store->upsertRobot({"r0", "hall", "{}", 1, 2, 0});
  const auto r1 = store->robot("r1");
  ASSERT_TRUE(r1);
  EXPECT_EQ(r1->map, "yard");
  EXPECT_EQ(r1->sensors_json, R"({"lidar":2})");
  EXPECT_EQ(r1->first_seen_ns, 100);
  EXPECT_EQ(r1->last_seen_ns, 950);
  EXPECT_EQ(r1->last_seq, 5u);
  const auto robots = store->robots();
  ASSERT_EQ(robots.size(), 2u);
  EXPECT_EQ(robots[0].robot_id, "r0");
  EXPECT_EQ(robots[1].robot_id, "r1");
  EXPECT_EQ(robots[1].last_seq, 5u);
}

TrajectoryPose pose(int64_t stamp_ns, uint64_t seq) {
  const double s = static_cast<double>(stamp_ns);
  return {stamp_ns, seq, {s, s + 0.5, -s}, {0.5, 0.5, -0.5, s / 1000}};
}

TEST(Store, TrajectoryReturnsPosesSinceStampInTimeOrderUpToLimit) {
  TempDir tmp;
  const auto store = Store::open(tmp.path());
  store->appendTrajectory("r1", std::vector{pose(30, 3), pose(10, 1), pose(20, 2)});
  store->appendTrajectory("r1", std::vector{pose(40, 4)});
  store->appendTrajectory("r2", std::vector{pose(15, 1)});
  const auto all = store->trajectory("r1", 0, 100);
  ASSERT_EQ(all.size(), 4u);
  for (size_t i = 0; i < all.size(); ++i) {
    const TrajectoryPose expected = pose(10 * static_cast<int64_t>(i + 1), i + 1);
    EXPECT_EQ(all[i].stamp_ns, expected.stamp_ns);
    EXPECT_EQ(all[i].seq, expected.seq);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(all[i].position_m[k], expected.position_m[k]);
    for (int k = 0; k < 4; ++k) EXPECT_EQ(all[i].orientation_wxyz[k], expected.orientation_wxyz[k]);
  }
  const auto since = store->trajectory("r1", 20, 2);
  ASSERT_EQ(since.size(), 2u);
  EXPECT_EQ(since[0].stamp_ns, 20);
  EXPECT_EQ(since[1].stamp_ns, 30);
  EXPECT_EQ(store->trajectory("r2", 0, 100).size(), 1u);
  EXPECT_TRUE(store->trajectory("r3", 0, 100).empty());
}

TEST(Store, EventsFilterByMapAndAfterIdUpToLimit) {
  TempDir tmp;
  const auto store = Store::open(tmp.path());
  const int64_t a1 = store->appendEvent({0, "a", "loop_closure", 10, R"({"from":1})"});
  const int64_t b1 = store->appendEvent({0, "b", "robot_joined", 20, "{}"});
  const int64_t a2 = store->appendEvent({0, "a", "loop_closure", 30, R"({"from":2})"});
  EXPECT_LT(a1, b1);
  EXPECT_LT(b1, a2);
  const auto of_a = store->events("a", 0, 10);
  ASSERT_EQ(of_a.size(), 2u);
  EXPECT_EQ(of_a[0].id, a1);
  EXPECT_EQ(of_a[0].map, "a");
  EXPECT_EQ(of_a[0].kind, "loop_closure");
  EXPECT_EQ(of_a[0].stamp_ns, 10);
  EXPECT_EQ(of_a[0].json, R"({"from":1})");
  EXPECT_EQ(of_a[1].id, a2);
  const auto after = store->events("", a1, 10);
  ASSERT_EQ(after.size(), 2u);
  EXPECT_EQ(after[0].id, b1);
  EXPECT_EQ(after[1].id, a2);
  const auto limited = store->events("", 0, 1);
  ASSERT_EQ(limited.size(), 1u);
  EXPECT_EQ(limited[0].id, a1);
}

TEST(Store, SnapshotIsReplaced) {
  TempDir tmp;
  const auto store = Store::open(tmp.path());
  EXPECT_FALSE(store->snapshot("hall"));
  store->putSnapshot({"hall", 10, binaryPayload(5000, 3)});
  store->putSnapshot({"hall", 20, binaryPayload(7000, 4)});
  store->putSnapshot({"yard", 5, ""});
  const auto hall = store->snapshot("hall");
  ASSERT_TRUE(hall);
  EXPECT_EQ(hall->map, "hall");
  EXPECT_EQ(hall->last_message_id, 20);
  EXPECT_EQ(hall->blob, binaryPayload(7000, 4));
  ASSERT_TRUE(store->snapshot("yard"));
  EXPECT_EQ(store->snapshot("yard")->blob, "");
}

TEST(Store, ReopenKeepsEveryTable) {
  TempDir tmp;
  const auto payload = binaryPayload(250'000, 9);
  int64_t event_id = 0;
  {
    const auto store = Store::open(tmp.path());
    store->ensureMap({"hall", 0.1, R"({"k":1})", 5});
    store->append(std::vector{message("hall", "r1", 1, payload), message("hall", "r1", 2, "small")});
    store->upsertRobot({"r1", "hall", "[]", 1, 2, 2});
    store->appendTrajectory("r1", std::vector{pose(10, 1)});
    event_id = store->appendEvent({0, "hall", "loop_closure", 7, "{}"});
    store->putSnapshot({"hall", 1, "snapshot bytes"});
  }
  const auto store = Store::open(tmp.path());
  EXPECT_EQ(store->messageCount(), 2u);
  const auto stored = allMessages(*store);
  ASSERT_EQ(stored.size(), 2u);
  expectSameRecord(stored[0].record, message("hall", "r1", 1, payload));
  ASSERT_EQ(store->maps().size(), 1u);
  EXPECT_EQ(store->maps()[0].params_json, R"({"k":1})");
  ASSERT_TRUE(store->robot("r1"));
  EXPECT_EQ(store->robot("r1")->sensors_json, "[]");
  ASSERT_EQ(store->trajectory("r1", 0, 10).size(), 1u);
  EXPECT_EQ(store->trajectory("r1", 0, 10)[0].position_m[1], 10.5);
  ASSERT_EQ(store->events("", 0, 10).size(), 1u);
  EXPECT_EQ(store->events("", 0, 10)[0].id, event_id);
  ASSERT_TRUE(store->snapshot("hall"));
  EXPECT_EQ(store->snapshot("hall")->blob, "snapshot bytes");
  // Appending continues the log after the reopen.
  EXPECT_TRUE(store->append(std::vector{message("hall", "r1", 2, "again")})[0].duplicate);
  EXPECT_GT(store->append(std::vector{message("hall", "r1", 3, "new")})[0].id, stored[1].id);
}

TEST(Store, UncreatableDataDirGivesErrorNamingIt) {
  TempDir tmp;
  const auto file = tmp.path() / "plain_file";
  std::ofstream(file) << "not a directory";
  const auto data_dir = file / "sub";
  const std::string error = storeErrorOf([&] { Store::open(data_dir); });
  EXPECT_NE(error.find(data_dir.string()), std::string::npos) << error;
  EXPECT_NE(error.find("Not a directory"), std::string::npos) << error;
}

TEST(Store, NewerSchemaVersionIsRefused) {
  TempDir tmp;
  { Store::open(tmp.path()); }
  const std::string newer = std::to_string(kSchemaVersion + 1);
  queryDirectly(tmp.path() / "rmap.db", "PRAGMA user_version = " + newer);
  ASSERT_EQ(queryDirectly(tmp.path() / "rmap.db", "PRAGMA user_version"), newer);
  const std::string error = storeErrorOf([&] { Store::open(tmp.path()); });
  EXPECT_NE(error.find("schema version " + newer), std::string::npos) << error;
  EXPECT_NE(error.find((tmp.path() / "rmap.db").string()), std::string::npos) << error;
}

LoopClosureRecord closure(const std::string& map, const std::string& source, const std::string& query_robot,
                          int64_t query_stamp_ns, const std::string& match_robot, int64_t match_stamp_ns) {
  return {0, map, source, query_robot, query_stamp_ns, match_robot, match_stamp_ns, 99, R"({"score":0.5})", std::nullopt};
}

LoopClosureFilter filter(std::string map = "", std::string robot = "", std::string source = "", int64_t after_id = 0,
                         size_t limit = 1000) {
  return {std::move(map), std::move(robot), std::move(source), after_id, limit};
}

TEST(Store, LoopClosuresAreStoredOnceAndFilteredByMapRobotSourceAndCursor) {
  TempDir tmp;
  auto store = Store::open(tmp.path());
  const std::optional<int64_t> a = store->appendLoopClosure(closure("hall", "camera", "r1", 10, "r2", 5));
  const std::optional<int64_t> b = store->appendLoopClosure(closure("hall", "geometry", "r2", 20, "r2", 3));
  const std::optional<int64_t> c = store->appendLoopClosure(closure("yard", "camera", "r3", 30, "r3", 1));
  ASSERT_TRUE(a && b && c);
  EXPECT_LT(*a, *b);
  EXPECT_LT(*b, *c);
  // The same closure found again (a replay of the log) is not stored twice.
  EXPECT_FALSE(store->appendLoopClosure(closure("hall", "camera", "r1", 10, "r2", 5)));
  // Another source or stamp is another closure.
  const std::optional<int64_t> d = store->appendLoopClosure(closure("hall", "laser_intensity", "r1", 10, "r2", 5));
  ASSERT_TRUE(d);

  const auto ids = [&](const LoopClosureFilter& f) {
    std::vector<int64_t> out;
    for (const LoopClosureRecord& r : store->loopClosures(f)) out.push_back(r.id);
    return out;
  };
  EXPECT_EQ(ids(filter()), (std::vector<int64_t>{*a, *b, *c, *d}));
  EXPECT_EQ(ids(filter("hall")), (std::vector<int64_t>{*a, *b, *d}));
  EXPECT_EQ(ids(filter("", "r2")), (std::vector<int64_t>{*a, *b, *d}));  // either side
  EXPECT_EQ(ids(filter("", "r1", "camera")), (std::vector<int64_t>{*a}));
  EXPECT_EQ(ids(filter("hall", "", "", *a)), (std::vector<int64_t>{*b, *d}));
  EXPECT_EQ(ids(filter("", "", "", 0, 2)), (std::vector<int64_t>{*a, *b}));

  const std::vector<LoopClosureRecord> read = store->loopClosures(filter("", "", "geometry"));
  ASSERT_EQ(read.size(), 1u);
  EXPECT_EQ(read[0].map, "hall");
  EXPECT_EQ(read[0].query_robot, "r2");
  EXPECT_EQ(read[0].query_stamp_ns, 20);
  EXPECT_EQ(read[0].match_robot, "r2");
  EXPECT_EQ(read[0].match_stamp_ns, 3);
  EXPECT_EQ(read[0].detected_ns, 99);
  EXPECT_EQ(read[0].json, R"({"score":0.5})");

  // Durable: a new process reads them back.
  store.reset();
  store = Store::open(tmp.path());
  EXPECT_EQ(ids(filter()), (std::vector<int64_t>{*a, *b, *c, *d}));
}

TEST(Store, VersionOneDatabaseGainsTheLoopClosureTableAndKeepsItsData) {
  TempDir tmp;
  {
    auto store = Store::open(tmp.path());
    const MessageRecord m = message("hall", "r1", 1, "payload");
    store->append(std::span(&m, 1));
  }
  // What a version-1 rmapd left behind.
  queryDirectly(tmp.path() / "rmap.db", "DROP TABLE loop_closures");
  queryDirectly(tmp.path() / "rmap.db", "PRAGMA user_version = 1");
  auto store = Store::open(tmp.path());
  EXPECT_EQ(queryDirectly(tmp.path() / "rmap.db", "PRAGMA user_version"), std::to_string(kSchemaVersion));
  EXPECT_EQ(store->messageCount(), 1u);
  EXPECT_TRUE(store->appendLoopClosure(closure("hall", "camera", "r1", 10, "r1", 5)));
  EXPECT_EQ(store->loopClosures(filter()).size(), 1u);
}

// A 2D pose graph can drop a closure it reported: the store keeps it, marked.
TEST(Store, AWithdrawnLoopClosureKeepsItsIdAndBodyAndIsMarkedOnce) {
  TempDir tmp;
  auto store = Store::open(tmp.path());
  const std::optional<int64_t> a = store->appendLoopClosure(closure("hall", "geometry", "r1", 10, "r2", 5));
  const std::optional<int64_t> b = store->appendLoopClosure(closure("hall", "geometry", "r1", 11, "r2", 5));
  ASSERT_TRUE(a && b);
  const std::optional<LoopClosureRecord> withdrawn =
      store->withdrawLoopClosure(closure("hall", "geometry", "r1", 10, "r2", 5), 1234);
  ASSERT_TRUE(withdrawn);
  EXPECT_EQ(withdrawn->id, *a);
  EXPECT_EQ(withdrawn->json, R"({"score":0.5})");
  EXPECT_EQ(withdrawn->withdrawn_ns, 1234);
  // Once: a replay of the log withdraws it again; and only a stored closure.
  EXPECT_FALSE(store->withdrawLoopClosure(closure("hall", "geometry", "r1", 10, "r2", 5), 5678));
  EXPECT_FALSE(store->withdrawLoopClosure(closure("hall", "camera", "r1", 10, "r2", 5), 5678));
  EXPECT_FALSE(store->withdrawLoopClosure(closure("yard", "geometry", "r1", 10, "r2", 5), 5678));
  const auto check = [&] {
    const std::vector<LoopClosureRecord> read = store->loopClosures(filter());
    ASSERT_EQ(read.size(), 2u);
    EXPECT_EQ(read[0].withdrawn_ns, 1234);
    EXPECT_FALSE(read[1].withdrawn_ns);
  };
  check();
  store.reset();  // durable
  store = Store::open(tmp.path());
  check();
}

TEST(Store, VersionTwoDatabaseGainsTheWithdrawnColumnAndKeepsItsClosures) {
  TempDir tmp;
  {
    auto store = Store::open(tmp.path());
    ASSERT_TRUE(store->appendLoopClosure(closure("hall", "geometry", "r1", 10, "r1", 5)));
  }
  // What a version-2 rmapd left behind.
  queryDirectly(tmp.path() / "rmap.db", "ALTER TABLE loop_closures DROP COLUMN withdrawn_ns");
  queryDirectly(tmp.path() / "rmap.db", "PRAGMA user_version = 2");
  auto store = Store::open(tmp.path());
  EXPECT_EQ(queryDirectly(tmp.path() / "rmap.db", "PRAGMA user_version"), std::to_string(kSchemaVersion));
  const std::vector<LoopClosureRecord> read = store->loopClosures(filter());
  ASSERT_EQ(read.size(), 1u);
  EXPECT_FALSE(read[0].withdrawn_ns);
  EXPECT_TRUE(store->withdrawLoopClosure(closure("hall", "geometry", "r1", 10, "r1", 5), 7));
}

TEST(Store, FileThatIsNoDatabaseIsRefused) {
  TempDir tmp;
  std::ofstream(tmp.path() / "rmap.db") << std::string(8192, 'x');
  const std::string error = storeErrorOf([&] { Store::open(tmp.path()); });
  EXPECT_NE(error.find((tmp.path() / "rmap.db").string()), std::string::npos) << error;
  EXPECT_NE(error.find("not a database"), std::string::npos) << error;
}

TEST(Store, FailedAppendWritesNothingAndTheStoreStaysUsable) {
  TempDir tmp;
  StoreOptions options;
  options.max_database_bytes = 2 << 20;  // the disk is "full" at 2 MiB
  const auto store = Store::open(tmp.path(), options);
  store->append(std::vector{message("m", "r", 1, "kept")});
  std::vector<MessageRecord> too_big = {message("m", "r", 2, "small")};
  for (uint64_t seq = 3; seq < 40; ++seq) too_big.push_back(message("m", "r", seq, binaryPayload(100'000, 5)));

  const std::string error = storeErrorOf([&] { store->append(too_big); });
  EXPECT_NE(error.find("full"), std::string::npos) << error;
  EXPECT_NE(error.find("append messages"), std::string::npos) << error;
  try {
    store->append(too_big);
    ADD_FAILURE() << "the batch fitted the second time";
  } catch (const StoreError& e) {
    EXPECT_EQ(e.reason(), "database or disk is full");  // the cause alone: no operation, no path
  }
  EXPECT_EQ(store->messageCount(), 1u);
  EXPECT_EQ(allMessages(*store).size(), 1u);
  EXPECT_EQ(store->lastSeq("r"), 1u);

  const auto retried = store->append(std::vector{message("m", "r", 2, "small")});
  EXPECT_FALSE(retried[0].duplicate);  // the failed batch left no trace
  EXPECT_EQ(store->messageCount(), 2u);
  EXPECT_EQ(store->lastSeq("r"), 2u);
}

TEST(Store, SeqOutsideTheStorableRangeIsRefused) {
  TempDir tmp;
  const auto store = Store::open(tmp.path());
  EXPECT_THROW(store->append(std::vector{message("m", "r", 1, ""), message("m", "r", 0, "")}), StoreError);
  EXPECT_THROW(store->append(std::vector{message("m", "r", uint64_t{1} << 63, "")}), StoreError);
  EXPECT_EQ(store->messageCount(), 0u);
  EXPECT_NO_THROW(store->append(std::vector{message("m", "r", (uint64_t{1} << 63) - 1, "")}));
  EXPECT_EQ(store->lastSeq("r"), (uint64_t{1} << 63) - 1);
}

}  // namespace
}  // namespace rmap::store
