#include "datasets/compressed_file.h"

#include <bzlib.h>
#include <zlib.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>

namespace rmap::datasets {
namespace {

constexpr size_t kChunk = 1 << 20;

[[noreturn]] void fail(const std::string& path, const std::string& problem) {
  throw std::runtime_error(path + ": " + problem);
}

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

File openOrThrow(const std::string& path) {
  File f(std::fopen(path.c_str(), "rb"));
  if (!f) fail(path, std::string("cannot open: ") + std::strerror(errno));
  return f;
}

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string readPlain(const std::string& path) {
  File f = openOrThrow(path);
  std::string out;
  std::string chunk(kChunk, '\0');
  size_t n;
  while ((n = std::fread(chunk.data(), 1, chunk.size(), f.get())) > 0) out.append(chunk.data(), n);
  if (std::ferror(f.get())) fail(path, std::string("read error: ") + std::strerror(errno));
  return out;
}

std::string readGzip(const std::string& path) {
  gzFile gz = gzopen(path.c_str(), "rb");
  if (gz == nullptr) fail(path, std::string("cannot open: ") + std::strerror(errno));
  std::unique_ptr<gzFile_s, int (*)(gzFile)> closer(gz, gzclose);
  gzbuffer(gz, 256 * 1024);
  std::string out;
  std::string chunk(kChunk, '\0');
  int n;
  while ((n = gzread(gz, chunk.data(), static_cast<unsigned>(chunk.size()))) > 0) out.append(chunk.data(), n);
  // gzread reports a truncated stream as a plain end of file; gzerror tells them apart.
  int err = Z_OK;
  const char* message = gzerror(gz, &err);
  if (n < 0 || err != Z_OK) fail(path, std::string("corrupt or truncated gzip data: ") + message);
  return out;
}

std::string bzipError(int code) {
  switch (code) {
    case BZ_UNEXPECTED_EOF: return "truncated bzip2 data";
    case BZ_DATA_ERROR: return "corrupt bzip2 data (CRC or block error)";
    case BZ_DATA_ERROR_MAGIC: return "data after the bzip2 stream is not a bzip2 stream";
    case BZ_MEM_ERROR: return "out of memory while decompressing bzip2";
    case BZ_IO_ERROR: return std::string("read error: ") + std::strerror(errno);
    default: return "bzip2 error " + std::to_string(code);
  }
}

std::string readBzip2(const std::string& path) {
  File f = openOrThrow(path);
  std::string out;
  std::string chunk(kChunk, '\0');
  // Bytes read past the end of one stream: the start of the next one, if any.
  std::string unused;
  while (true) {
    int err = BZ_OK;
    BZFILE* bz = BZ2_bzReadOpen(&err, f.get(), 0, 0, unused.data(), static_cast<int>(unused.size()));
    if (err != BZ_OK) {
      const int open_error = err;
      BZ2_bzReadClose(&err, bz);
      fail(path, bzipError(open_error));
    }
    while (err == BZ_OK) {
      const int n = BZ2_bzRead(&err, bz, chunk.data(), static_cast<int>(chunk.size()));
      if (err == BZ_OK || err == BZ_STREAM_END) out.append(chunk.data(), static_cast<size_t>(n));
    }
    if (err != BZ_STREAM_END) {
      int ignored;
      BZ2_bzReadClose(&ignored, bz);
      fail(path, bzipError(err));
    }
    void* rest = nullptr;
    int rest_size = 0;
    BZ2_bzReadGetUnused(&err, bz, &rest, &rest_size);
    unused.assign(static_cast<const char*>(rest), static_cast<size_t>(rest_size));
    BZ2_bzReadClose(&err, bz);
    if (unused.empty()) {
      const int c = std::fgetc(f.get());
      if (c == EOF) break;
      unused.push_back(static_cast<char>(c));
    }
  }
  return out;
}

}  // namespace

std::string readFileMaybeCompressed(const std::string& path) {
  unsigned char magic[4] = {0, 0, 0, 0};
  size_t got;
  {
    File f = openOrThrow(path);
    got = std::fread(magic, 1, sizeof magic, f.get());
  }
  const bool gzip = got >= 2 && magic[0] == 0x1f && magic[1] == 0x8b;
  const bool bzip2 = got == 4 && magic[0] == 'B' && magic[1] == 'Z' && magic[2] == 'h' && magic[3] >= '1' &&
                     magic[3] <= '9';
  if (gzip) return readGzip(path);
  if (bzip2) return readBzip2(path);
  if (endsWith(path, ".gz")) fail(path, "named .gz but does not start with the gzip magic bytes");
  if (endsWith(path, ".bz2")) fail(path, "named .bz2 but does not start with the bzip2 magic \"BZh\"");
  return readPlain(path);
}

}  // namespace rmap::datasets
