#pragma once
/// @file schema.h
/// The store's tables and their version (kept in `PRAGMA user_version`).
/// Private to the store.

#include "store/sqlite_connection.h"

namespace rmap::store {

/// Version of the schema this build reads and writes.
inline constexpr int kSchemaVersion = 3;

/// Creates the tables in a new database, upgrades an older one in place, or
/// checks that an existing one has a schema this build understands.
/// @throws StoreError when the database was written by a newer rmapd
void prepareSchema(Connection& writer);

}  // namespace rmap::store
