#pragma once
/// @file compressed_file.h
/// Whole-file reading with transparent gzip / bzip2 decompression.

#include <string>

namespace rmap::datasets {

/// Reads a file whole. Content starting with the gzip magic (1f 8b) is
/// gunzipped, content starting with "BZh1".."BZh9" is bunzipped (several
/// concatenated members or streams are joined, as gzip/bzip2 do); anything
/// else is returned as is. A `.gz` / `.bz2` name whose content lacks the
/// matching magic is an error rather than silently read raw.
/// The whole decompressed content is held in memory.
/// @throws std::runtime_error naming the path when the file cannot be opened
///         or read, or the archive is truncated or corrupt
std::string readFileMaybeCompressed(const std::string& path);

}  // namespace rmap::datasets
