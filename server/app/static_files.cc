#include "app/static_files.h"

#include <fcntl.h>
#include <openssl/evp.h>
#include <openssl/sha.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <system_error>
#include <utility>

#include "app/http_util.h"

namespace rmap::app {

namespace fs = std::filesystem;
namespace http = boost::beast::http;

namespace {

/// Every static file is revalidated: their URLs carry no version (no bundler, three at a fixed
/// path), so any max-age could pair a new index.html with stale modules after an update.
/// Revalidation costs one conditional request answered 304 from an fstat.
constexpr const char* kCacheControl = "no-cache";

constexpr const char* kNotInstalled =
    "the web viewer is not installed on this server: run `npm ci --prefix web` in the rmap source tree, "
    "or point web_root (--web-root) at an installed copy; the API under /v1 works without it";

ApiError notFound() { return ApiError(404, "not_found", "no such file"); }

/// Refuses segments that could leave a directory or cut a path short. The canonical-path check in
/// fileResponse() is the guard; this makes the answer a clear 400 rather than a 404.
void checkSegment(const std::string& segment) {
  if (segment.find('\0') != std::string::npos) {
    throw ApiError(400, "invalid_argument", "a NUL byte (%00) is not allowed in a file path");
  }
  // Segments were split on '/' before decoding, so a '/' in one came from %2F.
  if (segment.find('/') != std::string::npos) {
    throw ApiError(400, "invalid_argument", "an encoded '/' (%2F) is not allowed in a file path");
  }
  if (segment == "." || segment == "..") {
    throw ApiError(400, "invalid_argument", "'" + segment + "' is not allowed in a file path");
  }
}

/// Whether canonical `path` lies strictly below canonical `dir`, compared by component so
/// that /web/app2 is not inside /web/app.
bool isInside(const fs::path& path, const fs::path& dir) {
  const auto [d, p] = std::mismatch(dir.begin(), dir.end(), path.begin(), path.end());
  return d == dir.end() && p != path.end();
}

class FileDescriptor {
 public:
  explicit FileDescriptor(int fd) : fd_(fd) {}
  ~FileDescriptor() { ::close(fd_); }
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

/// Up to `size` bytes of an open file (fewer when it shrank since it was measured).
std::string readFile(int fd, size_t size) {
  std::string body(size, '\0');
  size_t done = 0;
  while (done < size) {
    const ssize_t n = ::read(fd, body.data() + done, size - done);
    if (n < 0) throw std::system_error(errno, std::generic_category(), "reading a web file");
    if (n == 0) break;
    done += static_cast<size_t>(n);
  }
  body.resize(done);
  return body;
}

/// `dir / relative` as a response, when its canonical path (symlinks resolved) stays inside the
/// canonical `dir` and is a regular file. Both are resolved per request, so installing or
/// updating the viewer needs no restart.
net::Response fileResponse(const net::Request& request, const fs::path& dir, const fs::path& relative) {
  std::error_code ec;
  const fs::path real_dir = fs::canonical(dir, ec);
  if (ec) throw notFound();
  const fs::path real = fs::canonical(dir / relative, ec);
  if (ec || !isInside(real, real_dir)) throw notFound();
  // O_NONBLOCK: opening a FIFO left in the web root must not stall an I/O thread.
  const int fd = ::open(real.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) throw notFound();
  const FileDescriptor file(fd);
  struct stat st {};
  // Measured on the open file, so the type, ETag and length describe what is read.
  if (::fstat(file.get(), &st) != 0 || !S_ISREG(st.st_mode)) throw notFound();  // no directory listings
  const int64_t mtime_ns = int64_t{st.st_mtim.tv_sec} * 1'000'000'000 + st.st_mtim.tv_nsec;
  // Quotes added last: `"\"" + std::to_string(…)` draws a false -Wrestrict from GCC 12 (bug 105329).
  const std::string etag = '"' + (std::to_string(st.st_size) + "-" + std::to_string(mtime_ns)) + '"';
  if (etagMatches(request, etag)) return notModified(request, etag);

  const std::string_view type = contentTypeFor(relative);
  net::Response response =
      bodyResponse(request, readFile(file.get(), static_cast<size_t>(st.st_size)), std::string(type));
  response.set(http::field::etag, etag);
  response.set(http::field::cache_control, kCacheControl);
  // Module scripts need their real type; never let a browser guess another.
  response.set("X-Content-Type-Options", "nosniff");
  if (type.starts_with("text/html")) {
    response.set("Content-Security-Policy", contentSecurityPolicy(response.body()));
  }
  return response;
}

std::string asciiLower(std::string_view text) {
  std::string lower(text);
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](char c) { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); });
  return lower;
}

bool isHtmlSpace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\f' || c == '\r'; }

std::string_view trimHtmlSpace(std::string_view text) {
  while (!text.empty() && isHtmlSpace(text.front())) text.remove_prefix(1);
  while (!text.empty() && isHtmlSpace(text.back())) text.remove_suffix(1);
  return text;
}

/// Where the script data starting at `from` ends: the next "</script" followed by a space, '/'
/// or '>' (HTML script data end tag), or the end of `lower`.
size_t scriptEnd(std::string_view lower, size_t from) {
  for (size_t at = lower.find("</script", from); at != std::string_view::npos; at = lower.find("</script", at + 1)) {
    const size_t next = at + 8;
    if (next == lower.size() || isHtmlSpace(lower[next]) || lower[next] == '/' || lower[next] == '>') return at;
  }
  return lower.size();
}

/// The text of every <script type="importmap"> element of `html` as the browser hashes it: the
/// bytes between the start tag and its end tag, with CRLF and lone CR read as LF (HTML input
/// preprocessing). Attributes are tokenised as HTML does (quoted or not, any case, any order);
/// the first `type` attribute counts.
std::vector<std::string> importMaps(std::string_view html) {
  const std::string lower = asciiLower(html);
  const size_t size = lower.size();
  std::vector<std::string> maps;
  for (size_t at = lower.find("<script"); at != std::string::npos; at = lower.find("<script", at + 1)) {
    size_t i = at + 7;
    if (i < size && !isHtmlSpace(lower[i]) && lower[i] != '/' && lower[i] != '>') continue;  // e.g. <scripts>
    std::optional<bool> importmap;
    while (i < size && lower[i] != '>') {
      if (isHtmlSpace(lower[i]) || lower[i] == '/') {
        ++i;
        continue;
      }
      const size_t name_start = i++;  // a name has at least one character, even '='
      while (i < size && !isHtmlSpace(lower[i]) && lower[i] != '=' && lower[i] != '>' && lower[i] != '/') ++i;
      const std::string_view name = std::string_view(lower).substr(name_start, i - name_start);
      while (i < size && isHtmlSpace(lower[i])) ++i;
      std::string_view value;
      if (i < size && lower[i] == '=') {
        ++i;
        while (i < size && isHtmlSpace(lower[i])) ++i;
        if (i < size && (lower[i] == '"' || lower[i] == '\'')) {
          const size_t close = lower.find(lower[i], i + 1);
          if (close == std::string::npos) return maps;  // the document ends inside the tag
          value = std::string_view(lower).substr(i + 1, close - i - 1);
          i = close + 1;
        } else {
          const size_t value_start = i;
          while (i < size && !isHtmlSpace(lower[i]) && lower[i] != '>') ++i;
          value = std::string_view(lower).substr(value_start, i - value_start);
        }
      }
      if (name == "type" && !importmap) importmap = trimHtmlSpace(value) == "importmap";
    }
    if (i >= size) break;
    const size_t content = i + 1;
    const size_t end = scriptEnd(lower, content);
    if (importmap.value_or(false)) {
      std::string text;
      for (size_t k = content; k < end; ++k) {
        if (html[k] != '\r') {
          text.push_back(html[k]);
        } else if (k + 1 == end || html[k + 1] != '\n') {
          text.push_back('\n');
        }
      }
      maps.push_back(std::move(text));
    }
    at = end;
  }
  return maps;
}

std::string sha256Base64(std::string_view text) {
  std::array<unsigned char, SHA256_DIGEST_LENGTH> digest{};
  SHA256(reinterpret_cast<const unsigned char*>(text.data()), text.size(), digest.data());
  std::array<unsigned char, 4 * ((SHA256_DIGEST_LENGTH + 2) / 3) + 1> base64{};  // with EVP's NUL
  const int length = EVP_EncodeBlock(base64.data(), digest.data(), static_cast<int>(digest.size()));
  return std::string(reinterpret_cast<const char*>(base64.data()), static_cast<size_t>(length));
}

}  // namespace

StaticFiles::StaticFiles(const fs::path& web_root) : root_(fs::absolute(web_root)) {}

std::optional<net::Response> StaticFiles::serve(const net::Request& request,
                                                const std::vector<std::string>& segments) const {
  const std::vector<std::string>& s = segments;
  const bool index = s.empty() || (s.size() == 1 && s[0] == "index.html");
  if (!index && s[0] != "app" && s[0] != "node_modules") return std::nullopt;
  if (request.method() != http::verb::get && request.method() != http::verb::head) {
    const std::string_view method(request.method_string().data(), request.method_string().size());
    throw ApiError::methodNotAllowed(method, "GET, HEAD");
  }
  for (const std::string& segment : s) checkSegment(segment);
  if (index) {
    if (missingViewerFile(root_)) throw ApiError(503, "viewer_not_installed", kNotInstalled);
    return fileResponse(request, root_, "index.html");
  }
  // The directory the file must stay in, named by the first `prefix` segments.
  fs::path dir;
  size_t prefix = 0;
  if (s[0] == "app") {
    dir = root_ / "app";
    prefix = 1;
  } else if (s.size() > 2 && s[1] == "three" && s[2] == "build") {
    dir = root_ / "node_modules" / "three" / "build";
    prefix = 3;
  } else if (s.size() > 3 && s[1] == "three" && s[2] == "examples" && s[3] == "jsm") {
    dir = root_ / "node_modules" / "three" / "examples" / "jsm";
    prefix = 4;
  }
  if (prefix == 0 || s.size() == prefix) throw notFound();
  fs::path relative;
  for (size_t i = prefix; i < s.size(); ++i) {
    if (s[i].front() == '.') throw notFound();  // dotfiles and dot-directories are private
    relative /= s[i];
  }
  return fileResponse(request, dir, relative);
}

std::optional<fs::path> missingViewerFile(const fs::path& web_root) {
  for (const fs::path& needed : {web_root / "index.html", web_root / "node_modules/three/build/three.module.js"}) {
    std::error_code ec;
    if (!fs::is_regular_file(needed, ec)) return needed;
  }
  return std::nullopt;
}

std::string_view contentTypeFor(const fs::path& file) {
  static constexpr std::pair<std::string_view, std::string_view> kTypes[] = {
      {".html", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},
      {".mjs", "text/javascript; charset=utf-8"},
      {".css", "text/css; charset=utf-8"},
      {".json", "application/json"},
      {".map", "application/json"},
      {".txt", "text/plain; charset=utf-8"},
      {".png", "image/png"},
      {".jpg", "image/jpeg"},
      {".jpeg", "image/jpeg"},
      {".gif", "image/gif"},
      {".webp", "image/webp"},
      {".svg", "image/svg+xml"},
      {".ico", "image/x-icon"},
      {".wasm", "application/wasm"},
      {".woff2", "font/woff2"},
      {".woff", "font/woff"},
      {".glb", "model/gltf-binary"},
      {".gltf", "model/gltf+json"},
      {".ktx2", "image/ktx2"},
  };
  const std::string extension = asciiLower(file.extension().string());
  for (const auto& [known, type] : kTypes) {
    if (extension == known) return type;
  }
  return "application/octet-stream";
}

std::string contentSecurityPolicy(std::string_view html) {
  std::string scripts = "'self'";
  for (const std::string& map : importMaps(html)) scripts += " 'sha256-" + sha256Base64(map) + "'";
  // 'self' covers WebSockets to this host and port too (CSP3: Chrome 71+, Firefox, Safari 16+).
  return "default-src 'self'; script-src " + scripts +
         "; connect-src 'self'; img-src 'self' data: blob:; style-src 'self' 'unsafe-inline'; "
         "object-src 'none'; base-uri 'none'; form-action 'self'; frame-ancestors 'none'";
}

}  // namespace rmap::app
