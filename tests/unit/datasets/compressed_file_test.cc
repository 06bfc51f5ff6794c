#include "datasets/compressed_file.h"

#include <bzlib.h>
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

namespace rmap::datasets {
namespace {

namespace fs = std::filesystem;

class CompressedFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rmap_compressed_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  std::string writePlain(const std::string& name, const std::string& bytes) const {
    std::ofstream(path(name), std::ios::binary) << bytes;
    return path(name);
  }

  std::string writeGzip(const std::string& name, const std::string& content) const {
    gzFile gz = gzopen(path(name).c_str(), "wb");
    EXPECT_NE(gz, nullptr);
    EXPECT_EQ(gzwrite(gz, content.data(), static_cast<unsigned>(content.size())), static_cast<int>(content.size()));
    EXPECT_EQ(gzclose(gz), Z_OK);
    return path(name);
  }

  /// Appends one bzip2 stream holding `content` to the file.
  std::string writeBzip2(const std::string& name, const std::string& content, const char* mode = "wb") const {
    std::FILE* f = std::fopen(path(name).c_str(), mode);
    EXPECT_NE(f, nullptr);
    int err = BZ_OK;
    BZFILE* bz = BZ2_bzWriteOpen(&err, f, 9, 0, 0);
    EXPECT_EQ(err, BZ_OK);
    BZ2_bzWrite(&err, bz, const_cast<char*>(content.data()), static_cast<int>(content.size()));
    EXPECT_EQ(err, BZ_OK);
    BZ2_bzWriteClose(&err, bz, 0, nullptr, nullptr);
    EXPECT_EQ(err, BZ_OK);
    std::fclose(f);
    return path(name);
  }

  std::string readRaw(const std::string& p) const {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }

  fs::path dir_;
};

/// Several MiB of varied text, more than one read chunk.
std::string bigText() {
  std::string s;
  for (int i = 0; s.size() < 3'000'000; ++i) s += std::to_string(i * 7919 % 100003) + " 1.25 -3.5\n";
  return s;
}

void expectThrowsNaming(const std::string& p, const std::string& part) {
  try {
    readFileMaybeCompressed(p);
    ADD_FAILURE() << p << " was accepted";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(p), std::string::npos) << what;
    EXPECT_NE(what.find(part), std::string::npos) << what;
  }
}

TEST_F(CompressedFileTest, ReadsPlainFiles) {
  EXPECT_EQ(readFileMaybeCompressed(writePlain("a.txt", "1 2 3\n4 5 6\n")), "1 2 3\n4 5 6\n");
  EXPECT_EQ(readFileMaybeCompressed(writePlain("empty.txt", "")), "");
  const std::string binary("\x00\x01\x1f\xff", 4);
  EXPECT_EQ(readFileMaybeCompressed(writePlain("b.bin", binary)), binary);
}

TEST_F(CompressedFileTest, DecompressesGzip) {
  EXPECT_EQ(readFileMaybeCompressed(writeGzip("a.gz", "hello\nworld\n")), "hello\nworld\n");
  EXPECT_EQ(readFileMaybeCompressed(writeGzip("empty.gz", "")), "");
  const std::string big = bigText();
  EXPECT_EQ(readFileMaybeCompressed(writeGzip("big.txt.gz", big)), big);
}

TEST_F(CompressedFileTest, DecompressesBzip2) {
  EXPECT_EQ(readFileMaybeCompressed(writeBzip2("a.bz2", "hello\nworld\n")), "hello\nworld\n");
  EXPECT_EQ(readFileMaybeCompressed(writeBzip2("empty.bz2", "")), "");
  const std::string big = bigText();
  EXPECT_EQ(readFileMaybeCompressed(writeBzip2("big.txt.bz2", big)), big);
}

TEST_F(CompressedFileTest, JoinsConcatenatedStreams) {
  writeBzip2("multi.bz2", "first\n");
  writeBzip2("multi.bz2", "second\n", "ab");
  EXPECT_EQ(readFileMaybeCompressed(path("multi.bz2")), "first\nsecond\n");
  const std::string gz = readRaw(writeGzip("one.gz", "first\n")) + readRaw(writeGzip("two.gz", "second\n"));
  EXPECT_EQ(readFileMaybeCompressed(writePlain("multi.gz", gz)), "first\nsecond\n");
}

TEST_F(CompressedFileTest, DetectsByMagicNotName) {
  EXPECT_EQ(readFileMaybeCompressed(writeGzip("gzip_without_suffix.dat", "abc")), "abc");
  EXPECT_EQ(readFileMaybeCompressed(writeBzip2("bzip2_without_suffix.dat", "abc")), "abc");
  expectThrowsNaming(writePlain("plain.gz", "1 2 3\n"), "gzip magic");
  expectThrowsNaming(writePlain("plain.bz2", "1 2 3\n"), "bzip2 magic");
}

TEST_F(CompressedFileTest, RejectsTruncatedAndCorruptArchives) {
  const std::string big = bigText();
  const std::string gz = readRaw(writeGzip("big.gz", big));
  for (size_t cut : {size_t{10}, gz.size() / 2, gz.size() - 4}) {
    expectThrowsNaming(writePlain("cut.gz", gz.substr(0, cut)), "gzip");
  }
  const std::string bz = readRaw(writeBzip2("big.bz2", big));
  for (size_t cut : {size_t{4}, size_t{20}, bz.size() / 2, bz.size() - 1}) {
    expectThrowsNaming(writePlain("cut.bz2", bz.substr(0, cut)), "bzip2");
  }
  std::string flipped = bz;
  for (size_t i = bz.size() / 3; i < bz.size() / 3 + 16; ++i) flipped[i] = static_cast<char>(flipped[i] ^ 0x5a);
  expectThrowsNaming(writePlain("corrupt.bz2", flipped), "bzip2");
  std::string gz_flipped = gz;
  for (size_t i = gz.size() / 3; i < gz.size() / 3 + 16; ++i) gz_flipped[i] = static_cast<char>(gz_flipped[i] ^ 0x5a);
  expectThrowsNaming(writePlain("corrupt.gz", gz_flipped), "gzip");
  expectThrowsNaming(writePlain("garbage_after.bz2", bz + "junk"), "bzip2");
}

TEST_F(CompressedFileTest, MissingFileNamesPath) { expectThrowsNaming(path("does_not_exist.txt"), "cannot open"); }

TEST(CompressedFileRealData, ReadsOctomapScanBz2) {
  const std::string p = std::string(RMAP_SHARED_DATA_DIR) + "/octomap/scan.dat.bz2";
  if (!std::filesystem::exists(p)) GTEST_SKIP() << p << " absent (shared data not available)";
  const std::string text = readFileMaybeCompressed(p);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 88206);
  EXPECT_EQ(text.substr(0, 31), "-0.0434742 -4.82982 0.499645\n0.");
}

}  // namespace
}  // namespace rmap::datasets
