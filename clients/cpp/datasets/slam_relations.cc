#include "datasets/slam_relations.h"

#include <cmath>
#include <iterator>

#include "datasets/carmen_log.h"
#include "datasets/compressed_file.h"
#include "datasets/text_fields.h"

namespace rmap::datasets {

std::vector<SlamRelation> parseSlamRelations(std::string_view text, const std::string& source) {
  std::vector<SlamRelation> relations;
  TextLines lines(text);
  std::string_view line;
  std::string_view fields[9];
  while (lines.next(line)) {
    const size_t n = splitFields(stripComment(line), fields, std::size(fields));
    if (n == 0) continue;
    if (n != 8) throwAt(source, lines.number(), "expected t1 t2 x y z roll pitch yaw, got " + std::to_string(n) + " fields");
    double v[6];
    for (size_t i = 0; i < 6; ++i) {
      v[i] = parseNumber(fields[2 + i], source, lines.number());
      if (!std::isfinite(v[i])) throwAt(source, lines.number(), "non-finite value \"" + std::string(fields[2 + i]) + "\"");
    }
    if (v[2] != 0.0 || v[3] != 0.0 || v[4] != 0.0) {
      throwAt(source, lines.number(), "not a planar relation (z, roll and pitch must be 0)");
    }
    relations.push_back({parseCarmenStampNs(fields[0], source, lines.number()),
                         parseCarmenStampNs(fields[1], source, lines.number()),
                         {v[0], v[1], slam2d::normalizeAngle(v[5])},
                         lines.number()});
  }
  return relations;
}

std::vector<SlamRelation> readSlamRelations(const std::string& path) {
  return parseSlamRelations(readFileMaybeCompressed(path), path);
}

}  // namespace rmap::datasets
