#include "datasets/ply_cloud.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <stdexcept>

#include "datasets/compressed_file.h"
#include "datasets/text_fields.h"

namespace rmap::datasets {
namespace {

enum class Type { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

bool typeOf(std::string_view name, Type& type) {
  static const std::pair<std::string_view, Type> kNames[] = {
      {"char", Type::kInt8},     {"int8", Type::kInt8},       {"uchar", Type::kUint8},  {"uint8", Type::kUint8},
      {"short", Type::kInt16},   {"int16", Type::kInt16},     {"ushort", Type::kUint16}, {"uint16", Type::kUint16},
      {"int", Type::kInt32},     {"int32", Type::kInt32},     {"uint", Type::kUint32},  {"uint32", Type::kUint32},
      {"float", Type::kFloat32}, {"float32", Type::kFloat32}, {"double", Type::kFloat64}, {"float64", Type::kFloat64}};
  for (const auto& [n, t] : kNames) {
    if (n == name) return type = t, true;
  }
  return false;
}

size_t sizeOf(Type t) {
  switch (t) {
    case Type::kInt8: case Type::kUint8: return 1;
    case Type::kInt16: case Type::kUint16: return 2;
    case Type::kInt32: case Type::kUint32: case Type::kFloat32: return 4;
    case Type::kFloat64: return 8;
  }
  return 0;
}

/// One binary value as double; `swap` when the file's byte order differs from the machine's.
double decode(const char* p, Type t, bool swap) {
  char b[8];
  const size_t n = sizeOf(t);
  std::memcpy(b, p, n);
  if (swap) {
    for (size_t i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
  }
  auto as = [&]<class T>(T) {
    T v;
    std::memcpy(&v, b, sizeof v);
    return static_cast<double>(v);
  };
  switch (t) {
    case Type::kInt8: return as(int8_t{});
    case Type::kUint8: return as(uint8_t{});
    case Type::kInt16: return as(int16_t{});
    case Type::kUint16: return as(uint16_t{});
    case Type::kInt32: return as(int32_t{});
    case Type::kUint32: return as(uint32_t{});
    case Type::kFloat32: return as(float{});
    case Type::kFloat64: return as(double{});
  }
  return 0.0;
}

struct Property {
  std::string name;
  Type type = Type::kFloat32;
  bool list = false;
};

struct Element {
  std::string name;
  size_t count = 0;
  std::vector<Property> properties;
};

enum class Format { kAscii, kBinaryLittle, kBinaryBig };

}  // namespace

PlyCloud parsePlyCloud(std::string_view content, const std::string& source) {
  auto fail = [&](const std::string& what) { throw std::runtime_error(source + ": " + what); };
  TextLines lines(content);
  std::string_view line;
  std::string_view f[8];
  if (!lines.next(line) || line != "ply") fail("not a PLY file (first line is not 'ply')");
  bool have_format = false, ended = false;
  Format format = Format::kAscii;
  std::vector<Element> elements;
  while (lines.next(line)) {
    const size_t n = splitFields(line, f, std::size(f));
    if (n == 0) continue;
    if (f[0] == "comment" || f[0] == "obj_info") continue;
    if (f[0] == "end_header") {
      ended = true;
      break;
    }
    if (f[0] == "format") {
      if (n != 3) throwAt(source, lines.number(), "format needs a name and a version");
      if (f[1] == "ascii") format = Format::kAscii;
      else if (f[1] == "binary_little_endian") format = Format::kBinaryLittle;
      else if (f[1] == "binary_big_endian") format = Format::kBinaryBig;
      else throwAt(source, lines.number(), "unknown format '" + std::string(f[1]) + "'");
      have_format = true;
    } else if (f[0] == "element") {
      if (n != 3) throwAt(source, lines.number(), "element needs a name and a count");
      const double count = parseNumber(f[2], source, lines.number());
      // Checked below 2^64 before the cast: a larger count does not convert.
      if (!(count >= 0 && count < 0x1p64) || count != std::floor(count)) {
        throwAt(source, lines.number(), "element count must be a whole number in [0, 2^64)");
      }
      elements.push_back({std::string(f[1]), static_cast<size_t>(count), {}});
    } else if (f[0] == "property") {
      if (elements.empty()) throwAt(source, lines.number(), "property before any element");
      Property p;
      Type count_type;
      if (n == 3 && typeOf(f[1], p.type)) {
        p.name = f[2];
      } else if (n == 5 && f[1] == "list" && typeOf(f[2], count_type) && typeOf(f[3], p.type)) {
        p.name = f[4], p.list = true;
      } else {
        throwAt(source, lines.number(), "unsupported property declaration '" + std::string(line) + "'");
      }
      elements.back().properties.push_back(p);
    } else {
      throwAt(source, lines.number(), "unknown header keyword '" + std::string(f[0]) + "'");
    }
  }
  if (!ended) fail("header has no end_header");
  if (!have_format) fail("header has no format line");

  size_t vertex_index = elements.size();
  for (size_t e = 0; e < elements.size(); ++e) {
    if (elements[e].name == "vertex") vertex_index = e;
  }
  if (vertex_index == elements.size()) fail("no vertex element");
  const Element& vertex = elements[vertex_index];
  int xyz[3] = {-1, -1, -1};
  for (size_t i = 0; i < vertex.properties.size(); ++i) {
    const Property& p = vertex.properties[i];
    if (p.list) fail("vertex property '" + p.name + "' is a list");
    for (int a = 0; a < 3; ++a) {
      if (p.name.size() == 1 && p.name[0] == "xyz"[a]) xyz[a] = static_cast<int>(i);
    }
  }
  for (int a = 0; a < 3; ++a) {
    if (xyz[a] < 0) fail(std::string("vertex has no property '") + "xyz"[a] + "'");
  }

  // The data starts right after the end_header line. Its size bounds the vertex count before
  // memory is taken for the vertices: binary ones take their stride, ascii ones a line of at
  // least two characters (the last one may lack its '\n'; short lines are refused below).
  size_t pos = lines.offset();
  if (format == Format::kAscii) {
    if (vertex.count > (content.size() - pos + 1) / 2) {
      fail("header declares " + std::to_string(vertex.count) + " vertices, more than the " +
           std::to_string(content.size() - pos) + " bytes of ascii data can hold");
    }
  } else {
    // Binary: the elements before the vertices are skipped, each checked against the data left.
    for (size_t e = 0; e <= vertex_index; ++e) {
      size_t stride = 0;
      for (const Property& p : elements[e].properties) {
        if (p.list) fail("element '" + elements[e].name + "' before the vertices has a list property (binary)");
        stride += sizeOf(p.type);
      }
      if ((content.size() - pos) / std::max<size_t>(stride, 1) < elements[e].count) {
        fail("binary data ends in element '" + elements[e].name + "' (" + std::to_string(elements[e].count) +
             " × " + std::to_string(stride) + " bytes declared)");
      }
      if (e != vertex_index) pos += stride * elements[e].count;
    }
  }

  PlyCloud cloud;
  cloud.points_m.resize(vertex.count);
  std::vector<std::vector<float>*> columns(vertex.properties.size(), nullptr);
  for (size_t i = 0; i < vertex.properties.size(); ++i) {
    if (static_cast<int>(i) != xyz[0] && static_cast<int>(i) != xyz[1] && static_cast<int>(i) != xyz[2]) {
      columns[i] = &cloud.scalars[vertex.properties[i].name];
      columns[i]->resize(vertex.count);
    }
  }
  auto store = [&](size_t v, size_t i, double value) {
    if (columns[i]) (*columns[i])[v] = static_cast<float>(value);
    for (int a = 0; a < 3; ++a) {
      if (static_cast<int>(i) == xyz[a]) cloud.points_m[v][a] = static_cast<float>(value);
    }
  };

  if (format == Format::kAscii) {
    for (size_t e = 0; e <= vertex_index; ++e) {
      for (size_t k = 0; k < elements[e].count; ++k) {
        if (!lines.next(line)) fail("ascii data ends in element '" + elements[e].name + "' " + std::to_string(k));
        if (e != vertex_index) continue;
        std::vector<std::string_view> values(vertex.properties.size() + 1);
        const size_t n = splitFields(line, values.data(), values.size());
        if (n != vertex.properties.size()) {
          throwAt(source, lines.number(),
                  "vertex needs " + std::to_string(vertex.properties.size()) + " values, got " + std::to_string(n));
        }
        for (size_t i = 0; i < n; ++i) store(k, i, parseNumber(values[i], source, lines.number()));
      }
    }
    return cloud;
  }

  const bool swap = (format == Format::kBinaryLittle) != (std::endian::native == std::endian::little);
  for (size_t k = 0; k < vertex.count; ++k) {
    for (size_t i = 0; i < vertex.properties.size(); ++i) {
      store(k, i, decode(content.data() + pos, vertex.properties[i].type, swap));
      pos += sizeOf(vertex.properties[i].type);
    }
  }
  return cloud;
}

PlyCloud readPlyCloud(const std::string& path) { return parsePlyCloud(readFileMaybeCompressed(path), path); }

}  // namespace rmap::datasets
