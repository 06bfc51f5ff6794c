#include "store/sqlite_connection.h"

#include <cstring>

namespace rmap::store {
namespace {

/// SQLite's message plus, for failures of the file system, the OS reason
/// (SQLite's own text for those is a generic "unable to open database file").
std::string reasonOf(sqlite3* db, int code) {
  std::string reason = db ? sqlite3_errmsg(db) : sqlite3_errstr(code);
  switch (code & 0xff) {
    case SQLITE_CANTOPEN:
    case SQLITE_IOERR:
    case SQLITE_FULL:
    case SQLITE_PERM:
    case SQLITE_READONLY:
      if (const int os_error = db ? sqlite3_system_errno(db) : 0; os_error != 0) {
        reason += " (";
        reason += std::strerror(os_error);
        reason += ')';
      }
      break;
    default:
      break;
  }
  return reason;
}

StoreError errorOf(std::string_view operation, const std::filesystem::path& file, sqlite3* db, int code) {
  std::string reason = reasonOf(db, code);
  return StoreError(std::string(operation) + " failed on " + file.string() + ": " + reason, reason);
}

}  // namespace

Connection::Connection(const std::filesystem::path& file, int flags) : file_(file) {
  const int code = sqlite3_open_v2(file.c_str(), &db_, flags | SQLITE_OPEN_NOMUTEX | SQLITE_OPEN_EXRESCODE, nullptr);
  if (code != SQLITE_OK) {
    const StoreError error = errorOf("open database", file_, db_, code);
    sqlite3_close(db_);  // a handle is returned even on failure
    throw error;
  }
}

Connection::~Connection() {
  for (auto& [sql, statement] : statements_) sqlite3_finalize(statement);
  sqlite3_close(db_);
}

void Connection::exec(const std::string& sql, std::string_view operation) {
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, nullptr) != SQLITE_OK) fail(operation);
}

sqlite3_stmt* Connection::prepared(std::string_view sql, std::string_view operation) {
  if (const auto found = statements_.find(sql); found != statements_.end()) return found->second;
  sqlite3_stmt* statement = nullptr;
  if (sqlite3_prepare_v3(db_, sql.data(), static_cast<int>(sql.size()), SQLITE_PREPARE_PERSISTENT, &statement,
                         nullptr) != SQLITE_OK)
    fail(operation);
  statements_.emplace(std::string(sql), statement);
  return statement;
}

void Connection::fail(std::string_view operation) const {
  throw errorOf(operation, file_, db_, sqlite3_extended_errcode(db_));
}

Statement::Statement(Connection& connection, std::string_view sql, std::string_view operation)
    : connection_(connection), statement_(connection.prepared(sql, operation)), operation_(operation) {}

Statement::~Statement() {
  sqlite3_reset(statement_);
}

void Statement::bind(int parameter, int64_t value) {
  if (sqlite3_bind_int64(statement_, parameter, value) != SQLITE_OK) connection_.fail(operation_);
}

void Statement::bind(int parameter, double value) {
  if (sqlite3_bind_double(statement_, parameter, value) != SQLITE_OK) connection_.fail(operation_);
}

void Statement::bindText(int parameter, std::string_view value) {
  // A null pointer would bind SQL NULL; an empty view must stay an empty string.
  if (sqlite3_bind_text64(statement_, parameter, value.empty() ? "" : value.data(), value.size(), SQLITE_STATIC,
                          SQLITE_UTF8) != SQLITE_OK)
    connection_.fail(operation_);
}

void Statement::bindBlob(int parameter, std::string_view value) {
  if (sqlite3_bind_blob64(statement_, parameter, value.empty() ? "" : value.data(), value.size(), SQLITE_STATIC) !=
      SQLITE_OK)
    connection_.fail(operation_);
}

bool Statement::step() {
  switch (sqlite3_step(statement_)) {
    case SQLITE_ROW:
      return true;
    case SQLITE_DONE:
      return false;
    default:
      connection_.fail(operation_);
  }
}

void Statement::reset() {
  sqlite3_reset(statement_);  // its return code repeats the last step's, already reported
}

bool Statement::isNull(int column) const {
  return sqlite3_column_type(statement_, column) == SQLITE_NULL;
}

int64_t Statement::int64At(int column) const {
  return sqlite3_column_int64(statement_, column);
}

double Statement::doubleAt(int column) const {
  return sqlite3_column_double(statement_, column);
}

std::string_view Statement::textAt(int column) const {
  const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(statement_, column));
  const auto size = static_cast<size_t>(sqlite3_column_bytes(statement_, column));  // after the text call: its size
  return text ? std::string_view(text, size) : std::string_view();
}

std::string_view Statement::blobAt(int column) const {
  const auto* blob = static_cast<const char*>(sqlite3_column_blob(statement_, column));
  const auto size = static_cast<size_t>(sqlite3_column_bytes(statement_, column));
  return blob ? std::string_view(blob, size) : std::string_view();  // an empty blob reads as a null pointer
}

Transaction::Transaction(Connection& connection, std::string_view operation)
    : connection_(connection), operation_(operation) {
  Statement(connection_, "BEGIN IMMEDIATE", operation_).step();
}

Transaction::~Transaction() {
  // SQLite rolls back by itself after some errors (e.g. SQLITE_FULL); only an
  // open transaction needs it.
  if (!sqlite3_get_autocommit(connection_.handle())) sqlite3_exec(connection_.handle(), "ROLLBACK", nullptr, nullptr, nullptr);
}

void Transaction::commit() {
  Statement(connection_, "COMMIT", operation_).step();
}

}  // namespace rmap::store
