#include "datasets/pcd_cloud.h"

#include <cstdint>
#include <cstring>
#include <stdexcept>

#include "datasets/compressed_file.h"
#include "datasets/text_fields.h"

namespace rmap::datasets {
namespace {

struct Field {
  std::string name;
  char type = 'F';  ///< I signed, U unsigned, F floating point
  size_t size = 4;  ///< bytes
  size_t count = 1;
  size_t offset = 0;  ///< bytes into a binary record
};

/// One binary value (host byte order: PCD files are written little-endian by PCL on x86) as double.
double decode(const char* p, const Field& f) {
  auto as = [p]<class T>(T) {
    T v;
    std::memcpy(&v, p, sizeof v);
    return static_cast<double>(v);
  };
  if (f.type == 'F') return f.size == 4 ? as(float{}) : as(double{});
  if (f.type == 'I') {
    switch (f.size) {
      case 1: return as(int8_t{});
      case 2: return as(int16_t{});
      case 4: return as(int32_t{});
      default: return as(int64_t{});
    }
  }
  switch (f.size) {
    case 1: return as(uint8_t{});
    case 2: return as(uint16_t{});
    case 4: return as(uint32_t{});
    default: return as(uint64_t{});
  }
}

size_t parseCount(std::string_view field, const std::string& source, size_t line, const char* what) {
  const double v = parseNumber(field, source, line);
  if (!(v >= 0.0) || v != static_cast<double>(static_cast<size_t>(v)) || v > 1e10) {
    throwAt(source, line, std::string(what) + " must be a whole number >= 0, not '" + std::string(field) + "'");
  }
  return static_cast<size_t>(v);
}

}  // namespace

PcdCloud parsePcdCloud(std::string_view content, const std::string& source) {
  TextLines lines(content);
  std::string_view line;
  std::vector<Field> fields;
  size_t width = 0, height = 1, points = 0;
  bool have_points = false, have_width = false;
  std::string data;
  constexpr size_t kMaxFields = 256;
  std::string_view f[kMaxFields + 1];
  size_t header_end = 0;
  while (data.empty()) {
    if (!lines.next(line)) throwAt(source, lines.number(), "header ends without a DATA line");
    const std::string_view text = stripComment(line);
    const size_t n = splitFields(text, f, kMaxFields + 1);
    if (n == 0) continue;
    if (n > kMaxFields) throwAt(source, lines.number(), "more than 256 fields");
    const std::string_view key = f[0];
    if (key == "VERSION" || key == "VIEWPOINT") continue;
    if (key == "FIELDS" || key == "COLUMNS") {
      fields.assign(n - 1, Field{});
      for (size_t i = 1; i < n; ++i) fields[i - 1].name = std::string(f[i]);
    } else if (key == "SIZE" || key == "TYPE" || key == "COUNT") {
      if (n - 1 != fields.size()) {
        throwAt(source, lines.number(), std::string(key) + " lists " + std::to_string(n - 1) + " values for " +
                                            std::to_string(fields.size()) + " FIELDS");
      }
      for (size_t i = 1; i < n; ++i) {
        Field& field = fields[i - 1];
        if (key == "TYPE") {
          if (f[i].size() != 1 || (f[i][0] != 'F' && f[i][0] != 'I' && f[i][0] != 'U')) {
            throwAt(source, lines.number(), "TYPE must be F, I or U, not '" + std::string(f[i]) + "'");
          }
          field.type = f[i][0];
        } else if (key == "SIZE") {
          field.size = parseCount(f[i], source, lines.number(), "SIZE");
          if (field.size != 1 && field.size != 2 && field.size != 4 && field.size != 8) {
            throwAt(source, lines.number(), "SIZE must be 1, 2, 4 or 8");
          }
        } else {
          field.count = parseCount(f[i], source, lines.number(), "COUNT");
        }
      }
    } else if (key == "WIDTH" && n == 2) {
      width = parseCount(f[1], source, lines.number(), "WIDTH");
      have_width = true;
    } else if (key == "HEIGHT" && n == 2) {
      height = parseCount(f[1], source, lines.number(), "HEIGHT");
    } else if (key == "POINTS" && n == 2) {
      points = parseCount(f[1], source, lines.number(), "POINTS");
      have_points = true;
    } else if (key == "DATA" && n == 2) {
      data = std::string(f[1]);
      header_end = lines.number();
    } else {
      throwAt(source, lines.number(), "unexpected header line '" + std::string(text) + "'");
    }
  }
  const size_t data_line = header_end;
  if (!have_points) points = width * height;
  if (have_width && width * height != points) {
    throwAt(source, data_line, "POINTS " + std::to_string(points) + " is not WIDTH·HEIGHT " +
                                   std::to_string(width * height));
  }
  int ix = -1, iy = -1, iz = -1, ii = -1;
  size_t record = 0;
  for (size_t i = 0; i < fields.size(); ++i) {
    Field& field = fields[i];
    if (field.type == 'F' && field.size != 4 && field.size != 8) throwAt(source, data_line, "F fields need SIZE 4 or 8");
    field.offset = record;
    record += field.size * field.count;
    int* slot = field.name == "x" ? &ix : field.name == "y" ? &iy : field.name == "z" ? &iz
                : field.name == "intensity" ? &ii : nullptr;
    if (!slot) continue;
    if (field.count != 1) throwAt(source, data_line, "field " + field.name + " must have COUNT 1");
    *slot = static_cast<int>(i);
  }
  if (ix < 0 || iy < 0 || iz < 0) throwAt(source, data_line, "FIELDS must include x, y and z");

  PcdCloud cloud;
  cloud.points_m.reserve(points);
  if (ii >= 0) cloud.intensities.reserve(points);
  if (data == "ascii") {
    // Values per line: every field's COUNT values in order.
    size_t values = 0;
    std::vector<size_t> first(fields.size());
    for (size_t i = 0; i < fields.size(); ++i) first[i] = values, values += fields[i].count;
    if (values > kMaxFields) throwAt(source, data_line, "more than 256 values per point");
    while (cloud.points_m.size() < points && lines.next(line)) {
      const size_t n = splitFields(line, f, kMaxFields + 1);
      if (n == 0) continue;
      if (n != values) {
        throwAt(source, lines.number(), std::to_string(n) + " values, expected " + std::to_string(values));
      }
      auto value = [&](int field) {
        return static_cast<float>(parseNumber(f[first[static_cast<size_t>(field)]], source, lines.number()));
      };
      cloud.points_m.emplace_back(value(ix), value(iy), value(iz));
      if (ii >= 0) cloud.intensities.push_back(value(ii));
    }
    if (cloud.points_m.size() < points) {
      throwAt(source, lines.number(), "truncated: " + std::to_string(cloud.points_m.size()) + " of " +
                                          std::to_string(points) + " points");
    }
    return cloud;
  }
  if (data == "binary_compressed") {
    throwAt(source, data_line, "DATA binary_compressed is not supported (save it as binary or ascii)");
  }
  if (data != "binary") throwAt(source, data_line, "DATA must be ascii or binary, not '" + data + "'");
  // The binary block starts right after the DATA line's newline.
  size_t start = 0;
  for (size_t k = 0; k < header_end; ++k) start = content.find('\n', start) + 1;
  if (record == 0 || (content.size() - start) / record < points) {
    throw std::runtime_error(source + ": offset " + std::to_string(start) + ": truncated: " + std::to_string(points) +
                             " points of " + std::to_string(record) + " bytes need " +
                             std::to_string(points * record) + " bytes, " + std::to_string(content.size() - start) +
                             " left");
  }
  for (size_t k = 0; k < points; ++k) {
    const char* p = content.data() + start + k * record;
    auto value = [&](int field) {
      const Field& fd = fields[static_cast<size_t>(field)];
      return static_cast<float>(decode(p + fd.offset, fd));
    };
    cloud.points_m.emplace_back(value(ix), value(iy), value(iz));
    if (ii >= 0) cloud.intensities.push_back(value(ii));
  }
  return cloud;
}

PcdCloud readPcdCloud(const std::string& path) { return parsePcdCloud(readFileMaybeCompressed(path), path); }

}  // namespace rmap::datasets
