#pragma once
/// @file store_copy.h
/// What rmapd's database holds, read from a copy while rmapd is down: SQLite
/// itself opens the copy (recovering its WAL there, so rmapd's next start
/// still finds the WAL a crash left and runs its own recovery).

#include <sqlite3.h>

#include <cstdint>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace rmap::testing {

struct StoreContents {
  std::string integrity;                              ///< PRAGMA integrity_check: "ok" when sound
  std::map<std::string, std::vector<uint64_t>> seqs;  ///< robot id → its logged seqs, ascending
};

/// Copies `<data_dir>/rmap.db` and its WAL into `scratch` and reads the copy.
/// @throws std::runtime_error when the copy does not open or the log cannot be read
inline StoreContents readStoreCopy(const std::filesystem::path& data_dir, const std::filesystem::path& scratch) {
  namespace fs = std::filesystem;
  fs::remove_all(scratch);
  fs::create_directories(scratch);
  for (const char* name : {"rmap.db", "rmap.db-wal"}) {
    if (fs::exists(data_dir / name)) fs::copy_file(data_dir / name, scratch / name);
  }
  sqlite3* db = nullptr;
  const fs::path file = scratch / "rmap.db";
  if (sqlite3_open_v2(file.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK) {
    const std::string error = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    throw std::runtime_error("cannot open the copy " + file.string() + ": " + error);
  }
  StoreContents out;
  const auto each_row = [&](const char* sql, auto&& row) {
    sqlite3_stmt* statement = nullptr;
    if (sqlite3_prepare_v2(db, sql, -1, &statement, nullptr) != SQLITE_OK) {
      const std::string error = sqlite3_errmsg(db);
      sqlite3_close(db);
      throw std::runtime_error(std::string(sql) + ": " + error);
    }
    while (sqlite3_step(statement) == SQLITE_ROW) row(statement);
    sqlite3_finalize(statement);
  };
  each_row("PRAGMA integrity_check", [&](sqlite3_stmt* s) {
    if (!out.integrity.empty()) out.integrity += "; ";
    out.integrity += reinterpret_cast<const char*>(sqlite3_column_text(s, 0));
  });
  each_row("SELECT robot_id, seq FROM messages ORDER BY robot_id, seq", [&](sqlite3_stmt* s) {
    out.seqs[reinterpret_cast<const char*>(sqlite3_column_text(s, 0))].push_back(
        static_cast<uint64_t>(sqlite3_column_int64(s, 1)));
  });
  sqlite3_close(db);
  return out;
}

}  // namespace rmap::testing
