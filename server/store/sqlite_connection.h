#pragma once
/// @file sqlite_connection.h
/// Thin RAII layer over the SQLite C API, private to the store: a connection
/// that keeps its prepared statements, a scoped use of one of them, and a
/// write transaction that rolls back unless committed. Every failure becomes
/// a StoreError naming the operation, the database file and SQLite's message.

#include <sqlite3.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <string_view>

#include "store/store.h"

namespace rmap::store {

/// One SQLite connection. Not thread-safe: its owner serialises all use
/// (opened with SQLITE_OPEN_NOMUTEX, so SQLite adds no locking of its own).
class Connection {
 public:
  /// @param flags SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, or SQLITE_OPEN_READONLY
  /// @throws StoreError naming the file and the reason (e.g. permission denied)
  Connection(const std::filesystem::path& file, int flags);
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  /// Runs statements that return nothing of interest (DDL, pragmas that set).
  void exec(const std::string& sql, std::string_view operation);
  /// The statement for `sql`, prepared on its first use and kept until the
  /// connection closes, so hot paths never re-parse SQL.
  sqlite3_stmt* prepared(std::string_view sql, std::string_view operation);
  /// @throws StoreError describing the connection's last error
  [[noreturn]] void fail(std::string_view operation) const;

  sqlite3* handle() const { return db_; }
  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
  sqlite3* db_ = nullptr;
  std::map<std::string, sqlite3_stmt*, std::less<>> statements_;
};

/// One execution of a cached statement. Resets it when going out of scope,
/// even on error, which ends its read snapshot and frees it for the next use.
/// Parameters and columns are numbered as in SQLite: parameters from 1
/// (`?1`), result columns from 0.
class Statement {
 public:
  Statement(Connection& connection, std::string_view sql, std::string_view operation);
  ~Statement();
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  void bind(int parameter, int64_t value);
  void bind(int parameter, double value);
  /// Binds without copying: `value` must stay valid until the statement is reset.
  void bindText(int parameter, std::string_view value);
  /// Binds without copying: `value` must stay valid until the statement is reset.
  void bindBlob(int parameter, std::string_view value);

  /// Advances to the next result row.
  /// @return true when a row is available, false when the statement is done
  bool step();
  /// Makes the statement ready to run again (bindings are kept until rebound).
  void reset();

  bool isNull(int column) const;
  int64_t int64At(int column) const;
  double doubleAt(int column) const;
  /// Valid until the next step() or reset().
  std::string_view textAt(int column) const;
  /// Valid until the next step() or reset().
  std::string_view blobAt(int column) const;

 private:
  Connection& connection_;
  sqlite3_stmt* statement_;
  std::string_view operation_;
};

/// A write transaction (BEGIN IMMEDIATE: takes the write lock up front, so a
/// busy database shows at the start instead of midway). Rolls back when
/// destroyed uncommitted, which is how a failed operation leaves no trace.
class Transaction {
 public:
  Transaction(Connection& connection, std::string_view operation);
  ~Transaction();
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;

  /// Makes the transaction durable (per the connection's synchronous setting).
  void commit();

 private:
  Connection& connection_;
  std::string_view operation_;
};

}  // namespace rmap::store
